// Mends contacts between two sheet edges: edges of different sheets (or of parts of one
// sheet far apart along it) that pass within a voxel or so of each other away from their
// corners. The commonest is a sheet's rim running along another sheet that it meets in the
// image (a T-junction the surface left a fraction of a voxel short): each of the rim's
// vertices is near the other sheet together with its neighbours, a contact along a line
// that the vertex mends leave, and the rim's edges pass over the other sheet's edges. The
// tetrahedra between them are as flat as the gap is narrow (on the rough network at
// r = 5, the four smallest angles of the volume mesh, 4.7-5.3 degrees, sat on such pairs).
// Both edges split where they pass closest and the two new vertices are one: the sheets
// are joined there, and the rim's vertices between such joins become point contacts that
// MendContacts then moves onto the other sheet. (Joining only rims to inner edges their
// faces stand on steeply, tried, left the networks at 4 of 12 meshes at 10 degrees
// against 7, bench/RESULTS.md.)
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/mesh/spatial_grid.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/plc_parts.h"

namespace sheetmesh {
namespace {

// Edges within this many degrees of parallel are not joined (see below).
const double kParallelCos = std::cos(20 * 3.14159265358979323846 / 180);

// The closest points of segments a-b and c-d: at a + s (b - a) and c + t (d - c).
double SegmentDistance(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double* s,
                       double* t) {
  const Vec3 u = b - a, w = d - c, r = a - c;
  const double uu = Dot(u, u), ww = Dot(w, w), uw = Dot(u, w), ur = Dot(u, r), wr = Dot(w, r);
  const double den = uu * ww - uw * uw;
  // Parallel (or nearly): any pair of closest points will do; the caller wants interior
  // ones, which the clamps below give where they exist.
  *s = den > 1e-12 * uu * ww ? std::clamp((uw * wr - ur * ww) / den, 0.0, 1.0) : 0.5;
  *t = ww > 0 ? (uw * *s + wr) / ww : 0.0;
  if (*t < 0) {
    *t = 0;
    *s = uu > 0 ? std::clamp(-ur / uu, 0.0, 1.0) : 0.0;
  } else if (*t > 1) {
    *t = 1;
    *s = uu > 0 ? std::clamp((uw - ur) / uu, 0.0, 1.0) : 0.0;
  }
  return Norm((a + u * *s) - (c + w * *t));
}

struct EdgeContact {
  uint32_t a, b, c, d;  // the two edges
  Vec3 at;              // where their joint vertex goes
  double distance;
};

}  // namespace

uint32_t MendEdgeContacts(SheetTriangles& s, std::vector<Vec3>& v, std::vector<uint8_t>& on_face,
                          double gap) {
  if (!(gap > 0) || s.faces.empty()) return 0;
  on_face.resize(v.size(), 0);
  SheetIndex index = IndexSheets(s, v, gap);
  const std::vector<std::vector<uint32_t>>& faces_of = index.faces_of;
  auto& edge_faces = index.edge_faces;
  const SpatialGrid& grid = index.grid;
  std::vector<EdgeContact> found;
  const double wedge_sine = std::sin(kWedgeKeptDegrees * 3.14159265358979323846 / 180);
  for (const auto& [key, faces] : edge_faces) {
    const uint32_t a = static_cast<uint32_t>(key >> 32), b = static_cast<uint32_t>(key);
    if ((on_face[a] & on_face[b]) != 0) continue;  // an edge in a box face
    Vec3 lo = v[a], hi = v[a];
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(v[a][k], v[b][k]) - gap;
      hi[k] = std::max(v[a][k], v[b][k]) + gap;
    }
    // Path lengths along the sheets from a and from b, found when first needed.
    absl::flat_hash_map<uint32_t, double> from_a, from_b;
    bool reached = false;
    EdgeContact best{0, 0, 0, 0, Vec3(), gap};
    absl::flat_hash_set<uint64_t> tried;
    grid.Query(lo, hi, [&](uint32_t f) {
      for (int k = 0; k < 3; ++k) {
        const uint32_t c = s.faces[f][k], d = s.faces[f][(k + 1) % 3];
        const uint64_t other = EdgeKey(c, d);
        // Each pair once, from its edge with the lower key; none sharing a corner.
        if (other <= key || !tried.insert(other).second) continue;
        if (c == a || c == b || d == a || d == b || (on_face[c] & on_face[d]) != 0) continue;
        // Edges running side by side are the vertices' contacts (each end onto the other
        // edge, or into its corner): joining them at one point would add a vertex to each.
        const Vec3 ab = v[b] - v[a], cd = v[d] - v[c];
        if (std::abs(Dot(ab, cd)) > kParallelCos * Norm(ab) * Norm(cd)) continue;
        double sa, tc;
        const double dist = SegmentDistance(v[a], v[b], v[c], v[d], &sa, &tc);
        if (!(dist < best.distance)) continue;
        const Vec3 p = v[a] + (v[b] - v[a]) * sa, q = v[c] + (v[d] - v[c]) * tc;
        // Near a corner it is a vertex's contact (MendContacts').
        if (Norm(p - v[a]) < gap || Norm(p - v[b]) < gap || Norm(q - v[c]) < gap ||
            Norm(q - v[d]) < gap) {
          continue;
        }
        // A wedge of a junction or a fold (reached along the sheets about as soon as
        // across) is the rock's, as for the vertices (kReachFactor).
        const double limit = kReachFactor * dist / wedge_sine;
        if (!reached) {
          const double most = kReachFactor * gap / wedge_sine;
          for (const auto& [x, along] : ReachAlongSheets(a, most, v, s.faces, faces_of)) {
            from_a[x] = along;
          }
          for (const auto& [x, along] : ReachAlongSheets(b, most, v, s.faces, faces_of)) {
            from_b[x] = along;
          }
          reached = true;
        }
        bool wedge = false;
        for (const uint32_t x : {c, d}) {
          double path = 1e300;
          if (auto it = from_a.find(x); it != from_a.end()) path = Norm(p - v[a]) + it->second;
          if (auto it = from_b.find(x); it != from_b.end()) {
            path = std::min(path, Norm(p - v[b]) + it->second);
          }
          wedge = wedge || path + Norm(v[x] - q) <= limit;
        }
        if (wedge) continue;
        // The edge on more faces (a junction's, or an inner edge against a rim) keeps its
        // line; between equals the joint is halfway.
        const size_t mine = faces.size(), their = edge_faces[other].size();
        const Vec3 at = mine > their ? p : their > mine ? q : (p + q) * 0.5;
        best = {a, b, c, d, at, dist};
      }
    });
    if (best.distance < gap) found.push_back(best);
  }
  if (found.empty()) return 0;
  std::sort(found.begin(), found.end(),
            [](const EdgeContact& x, const EdgeContact& y) { return x.distance < y.distance; });
  // Each face takes part in one contact; the nearest first.
  std::vector<uint8_t> busy(s.faces.size(), 0);
  std::vector<EdgeContact> round;
  for (const EdgeContact& e : found) {
    const std::vector<uint32_t>& f1 = edge_faces[EdgeKey(e.a, e.b)];
    const std::vector<uint32_t>& f2 = edge_faces[EdgeKey(e.c, e.d)];
    bool taken = false;
    for (uint32_t f : f1) taken = taken || busy[f];
    for (uint32_t f : f2) taken = taken || busy[f];
    if (taken) continue;
    for (uint32_t f : f1) busy[f] = 1;
    for (uint32_t f : f2) busy[f] = 1;
    round.push_back(e);
  }
  // Applied together; those whose faces then clash or repeat a triangle are left out.
  const uint32_t made = ApplyLeavingClashesOut(
      round.size(),
      [&](const std::vector<size_t>& kept, SheetTriangles& out, std::vector<Vec3>& moved,
          std::vector<int>& owner) {
        owner.assign(out.faces.size(), -1);
        for (size_t i = 0; i < kept.size(); ++i) {
          const EdgeContact& e = round[kept[i]];
          const uint32_t w = static_cast<uint32_t>(moved.size());
          moved.push_back(e.at);
          const int by = static_cast<int>(i);
          SplitEdgeFaces(e.a, e.b, w, edge_faces[EdgeKey(e.a, e.b)], by, out, owner);
          SplitEdgeFaces(e.c, e.d, w, edge_faces[EdgeKey(e.c, e.d)], by, out, owner);
        }
      },
      s, v, nullptr);
  on_face.resize(v.size(), 0);
  return made;
}

}  // namespace sheetmesh
