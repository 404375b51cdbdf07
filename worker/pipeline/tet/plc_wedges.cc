// The narrowest wedges of the PLC: where facets meet in an edge at an angle θ (two sheets
// at a shallow junction, a sheet folded sharply, a sheet meeting a box face at a grazing
// angle), the tetrahedra in that wedge have a dihedral angle of at most θ at the edge. No
// conforming mesh does better, so the report gives the bound beside the mesh's own angle.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "worker/pipeline/tet/plc.h"
#include "worker/pipeline/tet/plc_parts.h"

namespace sheetmesh {
namespace {

struct EdgeFans {
  std::vector<Vec3> sides;     // unit directions into each facet, across the edge
  std::vector<Vec3> outwards;  // outward normals of the box faces the edge lies in
};

}  // namespace

std::vector<EdgeWedge> WedgesAroundEdge(const Vec3& e, const std::vector<Vec3>& sides) {
  std::vector<EdgeWedge> out;
  if (sides.size() < 2) return out;
  constexpr double kDegrees = 180.0 / std::numbers::pi;
  const Vec3 x = sides[0], y = Cross(e, x);
  std::vector<double> angle;
  for (const Vec3& s : sides) angle.push_back(std::atan2(Dot(s, y), Dot(s, x)));
  std::sort(angle.begin(), angle.end());
  for (size_t i = 0; i < angle.size(); ++i) {
    const double from = angle[i];
    const double to = i + 1 < angle.size() ? angle[i + 1] : angle[0] + 2 * std::numbers::pi;
    const double mid = 0.5 * (from + to);
    out.push_back({(to - from) * kDegrees, x * std::cos(mid) + y * std::sin(mid)});
  }
  return out;
}

WedgeBound MeasureWedges(const Plc& plc, double below_degrees) {
  WedgeBound bound;
  const std::vector<Vec3>& v = plc.vertices;
  const Vec3 extent = plc.box_hi - plc.box_lo;
  const double tol = 1e-9 * std::max({extent.x, extent.y, extent.z, 1e-300});
  // Which box faces (bits 0..5: -x, +x, -y, +y, -z, +z) a vertex lies in.
  auto faces_of = [&](const Vec3& p) {
    const double lo[3] = {plc.box_lo.x, plc.box_lo.y, plc.box_lo.z};
    const double hi[3] = {plc.box_hi.x, plc.box_hi.y, plc.box_hi.z};
    const double c[3] = {p.x, p.y, p.z};
    int bits = 0;
    for (int k = 0; k < 3; ++k) {
      if (std::abs(c[k] - lo[k]) <= tol) bits |= 1 << (2 * k);
      if (std::abs(c[k] - hi[k]) <= tol) bits |= 1 << (2 * k + 1);
    }
    return bits;
  };
  absl::flat_hash_map<uint64_t, EdgeFans> fans;
  for (const Face& t : plc.sheet_triangles) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[k], b = t[(k + 1) % 3], o = t[(k + 2) % 3];
      const uint32_t lo = std::min(a, b), hi = std::max(a, b);
      const Vec3 e = Normalized(v[hi] - v[lo]);
      const Vec3 side = v[o] - v[lo];
      const Vec3 across = side - e * Dot(side, e);
      if (!(Norm(across) > 0)) continue;
      EdgeFans& fan = fans[EdgeKey(a, b)];
      fan.sides.push_back(Normalized(across));
      if (fan.sides.size() == 1) {
        const int shared = faces_of(v[a]) & faces_of(v[b]);
        for (int f = 0; f < 6; ++f) {
          if (!(shared & (1 << f))) continue;
          Vec3 n(0, 0, 0);
          (f / 2 == 0 ? n.x : f / 2 == 1 ? n.y : n.z) = (f % 2) ? 1.0 : -1.0;
          fan.outwards.push_back(n);
          // The box face on both sides of the edge.
          const Vec3 in_face = Normalized(Cross(n, e));
          fan.sides.push_back(in_face);
          fan.sides.push_back(in_face * -1.0);
        }
      }
    }
  }
  for (const auto& [key, fan] : fans) {
    if (fan.sides.size() < 2) continue;  // a rim edge: the sheet alone there
    const Vec3 lo = v[key >> 32], hi = v[key & 0xffffffffu];
    double narrowest = 360;
    for (const EdgeWedge& w : WedgesAroundEdge(Normalized(hi - lo), fan.sides)) {
      // One facet's side twice (a box face and a sheet in it) makes no wedge.
      if (w.degrees <= 1e-9) continue;
      bool outside = false;
      for (const Vec3& n : fan.outwards) outside = outside || Dot(w.middle, n) > 0;
      if (!outside) narrowest = std::min(narrowest, w.degrees);
    }
    bound.narrowest_degrees = std::min(bound.narrowest_degrees, narrowest);
    if (narrowest < below_degrees) ++bound.narrow_edges;
  }
  return bound;
}

}  // namespace sheetmesh
