// Collapses sheet edges far shorter than a voxel or two: TetGen must keep every sheet edge
// (it may not split a facet, -Y), and an edge of 1.7 voxels among edges of 25 pins a
// tetrahedron as flat as the edge is short, with all four corners on the sheet.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/plc_parts.h"

namespace sheetmesh {
namespace {

constexpr double kJunctionTurnDegrees = 1.0;  // the most a face on a junction turns
constexpr double kJunctionStraight = 0.1;     // voxels: how near the line without it a
                                              // junction vertex collapsed along it lies

}  // namespace

uint32_t CollapseShortEdges(SheetTriangles& s, std::vector<Vec3>& v,
                            const std::vector<uint8_t>& on_face, double max_length) {
  if (!(max_length > 0)) return 0;
  const double max_turn_cos = std::cos(30 * std::numbers::pi / 180);
  // A face on a junction turns no further than this: the sheets keep their angle there.
  const double max_junction_turn_cos = std::cos(kJunctionTurnDegrees * std::numbers::pi / 180);
  uint32_t collapsed = 0;
  for (int round = 0; round < 3; ++round) {
    std::vector<std::vector<uint32_t>> faces_of(v.size());
    absl::flat_hash_map<uint64_t, std::vector<uint32_t>> faces_on;  // edge -> faces
    auto key = [](uint32_t a, uint32_t b) {
      return (uint64_t{std::min(a, b)} << 32) | std::max(a, b);
    };
    for (uint32_t f = 0; f < s.faces.size(); ++f) {
      for (int k = 0; k < 3; ++k) {
        faces_of[s.faces[f][k]].push_back(f);
        faces_on[key(s.faces[f][k], s.faces[f][(k + 1) % 3])].push_back(f);
      }
    }
    // The junctions: edges of three or more faces, or of two of different pieces; the
    // vertices on them, and the faces along them.
    std::vector<uint8_t> on_junction(v.size(), 0), face_on_junction(s.faces.size(), 0);
    absl::flat_hash_map<uint64_t, bool> junction_edge;
    for (const auto& [e, faces] : faces_on) {
      const bool j =
          faces.size() >= 3 || (faces.size() == 2 && s.piece[faces[0]] != s.piece[faces[1]]);
      if (!j) continue;
      junction_edge[e] = true;
      on_junction[e >> 32] = on_junction[static_cast<uint32_t>(e)] = 1;
      for (uint32_t f : faces) face_on_junction[f] = 1;
    }
    std::vector<std::pair<double, uint64_t>> short_edges;
    for (const auto& [e, faces] : faces_on) {
      const uint32_t a = static_cast<uint32_t>(e >> 32), b = static_cast<uint32_t>(e);
      const double len = Norm(v[a] - v[b]);
      if (len < max_length) short_edges.push_back({len, e});
    }
    if (short_edges.empty()) break;
    std::sort(short_edges.begin(), short_edges.end());  // shortest first, then by key
    const SheetTriangles before = s;
    const std::vector<Vec3> before_v = v;
    std::vector<uint8_t> busy(v.size(), 0), drop(s.faces.size(), 0);
    uint32_t count = 0;
    for (const auto& [len, e] : short_edges) {
      uint32_t a = static_cast<uint32_t>(e >> 32), b = static_cast<uint32_t>(e);
      if (busy[a] || busy[b]) continue;
      // A vertex on a junction stays there: the other comes to it. Two on one only along it,
      // where the line runs straight on (the one left within kJunctionStraight of it).
      if (on_junction[b] && !on_junction[a]) std::swap(a, b);
      if (on_junction[b]) {
        if (!junction_edge.contains(e)) continue;
        bool straight = true;
        for (const auto& [f, unused] : junction_edge) {
          const uint32_t x = static_cast<uint32_t>(f >> 32), y = static_cast<uint32_t>(f);
          if (f == e || (x != b && y != b)) continue;
          // The line goes on from b to o; without b, from a to o: b must lie on a-o.
          const uint32_t o = x == b ? y : x;
          const Vec3 d = v[o] - v[a];
          const double len2 = Norm2(d);
          const double t = len2 > 0 ? std::clamp(Dot(v[b] - v[a], d) / len2, 0.0, 1.0) : 0.0;
          straight = straight && Norm(v[a] + d * t - v[b]) <= kJunctionStraight;
        }
        if (!straight) continue;
      }
      // Where it goes: a vertex on the box stays there (both on it: only on the same faces);
      // so does one on a junction.
      if (!on_junction[a] && on_face[b] != 0 && on_face[a] == 0) std::swap(a, b);
      if (on_face[b] != 0 && on_face[a] != on_face[b]) continue;
      if (on_junction[a] && on_face[b] != 0) continue;
      const Vec3 to =
          on_junction[a] || (on_face[a] != 0 && on_face[b] == 0) ? v[a] : (v[a] + v[b]) * 0.5;
      // The link condition: the vertices joined to both are exactly the faces' third corners
      // on a-b, so the collapse makes no new fold or hole.
      const std::vector<uint32_t>& on_ab = faces_on[e];
      std::vector<uint32_t> third, common;
      for (uint32_t f : on_ab) {
        for (uint32_t x : s.faces[f]) {
          if (x != a && x != b) third.push_back(x);
        }
      }
      std::vector<uint32_t> na, nb;
      for (uint32_t f : faces_of[a])
        for (uint32_t x : s.faces[f]) na.push_back(x);
      for (uint32_t f : faces_of[b])
        for (uint32_t x : s.faces[f]) nb.push_back(x);
      for (auto* n : {&na, &nb, &third}) {
        std::sort(n->begin(), n->end());
        n->erase(std::unique(n->begin(), n->end()), n->end());
      }
      std::set_intersection(na.begin(), na.end(), nb.begin(), nb.end(), std::back_inserter(common));
      common.erase(std::remove_if(common.begin(), common.end(),
                                  [&](uint32_t x) { return x == a || x == b; }),
                   common.end());
      if (common != third) continue;
      // The faces that stay turn no further than 30 degrees and do not become flat.
      bool ok = true;
      for (const uint32_t w : {a, b}) {
        for (uint32_t f : faces_of[w]) {
          Face t = s.faces[f];
          if (std::find(t.begin(), t.end(), a) != t.end() &&
              std::find(t.begin(), t.end(), b) != t.end())
            continue;  // on a-b: goes
          const Triangle old = {v[t[0]], v[t[1]], v[t[2]]};
          Triangle now = old;
          for (int k = 0; k < 3; ++k) {
            if (t[k] == a || t[k] == b) now[k] = to;
          }
          const Vec3 n0 = AreaVector(old), n1 = AreaVector(now);
          const double turn = face_on_junction[f] ? max_junction_turn_cos : max_turn_cos;
          ok =
              ok && Dot(n0, n1) > turn * Norm(n0) * Norm(n1) && AngleRangeDegrees(now).second < 170;
        }
      }
      if (!ok) continue;
      v[a] = to;
      for (uint32_t f : on_ab) drop[f] = 1;
      for (uint32_t f : faces_of[b]) {
        for (uint32_t& x : s.faces[f]) {
          if (x == b) x = a;
        }
      }
      busy[a] = busy[b] = 1;
      for (uint32_t x : na) busy[x] = 1;
      for (uint32_t x : nb) busy[x] = 1;
      ++count;
    }
    if (count == 0) break;
    s = Without(s, drop);
    TriangleMesh check;
    check.vertices = v;
    check.faces = s.faces;
    if (!FindSelfIntersections(check, 1, 1.0).empty()) {  // undo the round
      s = before;
      v = before_v;
      break;
    }
    collapsed += count;
  }
  return collapsed;
}

}  // namespace sheetmesh
