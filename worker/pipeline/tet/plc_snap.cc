#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <set>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/plc_parts.h"

namespace sheetmesh {
namespace {

constexpr int kSnapRounds = 5;  // rounds of snapping at most (holding back clashing vertices)

// Merges vertices within `merge` of an earlier one into it (snapping can bring vertices
// together): returns each vertex's representative; the faces a merged vertex lies on pass
// to its representative.
std::vector<uint32_t> MergeNearDuplicates(const std::vector<Vec3>& v, double merge,
                                          std::vector<uint8_t>* on_face, uint32_t* merged) {
  std::vector<uint32_t> rep(v.size());
  std::iota(rep.begin(), rep.end(), 0u);
  absl::flat_hash_map<uint64_t, std::vector<uint32_t>> cells;
  const double cell = std::max(merge, 1e-9) * 2;
  auto key = [&](int64_t x, int64_t y, int64_t z) {
    return (static_cast<uint64_t>(x & 0x1FFFFF) << 42) |
           (static_cast<uint64_t>(y & 0x1FFFFF) << 21) | static_cast<uint64_t>(z & 0x1FFFFF);
  };
  for (uint32_t i = 0; i < v.size(); ++i) {
    const int64_t cx = std::llround(v[i].x / cell), cy = std::llround(v[i].y / cell),
                  cz = std::llround(v[i].z / cell);
    bool found = false;
    for (int dz = -1; dz <= 1 && !found; ++dz)
      for (int dy = -1; dy <= 1 && !found; ++dy)
        for (int dx = -1; dx <= 1 && !found; ++dx) {
          auto it = cells.find(key(cx + dx, cy + dy, cz + dz));
          if (it == cells.end()) continue;
          for (uint32_t j : it->second) {
            if (Norm(v[i] - v[j]) <= merge) {
              rep[i] = j;
              (*on_face)[j] |= (*on_face)[i];
              found = true;
              break;
            }
          }
        }
    if (found) {
      ++*merged;
    } else {
      cells[key(cx, cy, cz)].push_back(i);
    }
  }
  return rep;
}

// The sheets' triangles on the merged vertices that are still triangles and do not lie in
// a box face (each once).
SheetTriangles KeepTriangles(const TriangleMesh& sheets, const std::vector<Vec3>& v,
                             const std::vector<uint32_t>& rep, const std::vector<uint8_t>& on_face,
                             uint32_t* dropped) {
  SheetTriangles st;
  std::set<std::array<uint32_t, 3>> seen;
  for (size_t f = 0; f < sheets.faces.size(); ++f) {
    Face t = {rep[sheets.faces[f][0]], rep[sheets.faces[f][1]], rep[sheets.faces[f][2]]};
    std::array<uint32_t, 3> s = t;
    std::sort(s.begin(), s.end());
    const bool in_face = (on_face[t[0]] & on_face[t[1]] & on_face[t[2]]) != 0;
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || in_face || !seen.insert(s).second ||
        Area({v[t[0]], v[t[1]], v[t[2]]}) < 1e-9) {
      ++*dropped;
      continue;
    }
    st.faces.push_back(t);
    st.source.push_back(static_cast<uint32_t>(f));
    st.piece.push_back(sheets.face_piece.size() == sheets.faces.size() ? sheets.face_piece[f] : 0);
    st.thickness.push_back(sheets.face_thickness_voxels.size() == sheets.faces.size()
                               ? sheets.face_thickness_voxels[f]
                               : 0.f);
  }
  return st;
}

// One round of snapping: v moved onto the box faces within reach (snap_voxels for the
// vertices held back), on_face set. Returns, per vertex, whether it snapped from beyond
// snap_voxels; counts the vertices that moved.
std::vector<uint8_t> SnapVertices(const TriangleMesh& sheets, const Vec3& lo, const Vec3& hi,
                                  const PlcOptions& options, const std::vector<uint8_t>& hold,
                                  SnappedSheets* s, uint32_t* snapped) {
  const double reach = std::max(options.snap_voxels, options.snap_clear_voxels);
  std::vector<uint8_t> wide(sheets.vertices.size(), 0);
  std::vector<Vec3>& v = s->v;
  std::vector<uint8_t>& on_face = s->on_face;
  v = sheets.vertices;
  on_face.assign(v.size(), 0);
  // A vertex beyond snap_voxels of a face that the sheets take to it within reach (a vertex
  // within snap_voxels of it as given, kReachFactor d / sin(kWedgeKeptDegrees) away along them)
  // meets the face in a wedge, not across a gap: it stays (a sheet that ends on the box leaves the
  // vertices near its end where they are).
  std::vector<std::vector<uint32_t>> faces_of(v.size());
  for (uint32_t f = 0; f < sheets.faces.size(); ++f) {
    for (uint32_t x : sheets.faces[f]) faces_of[x].push_back(f);
  }
  const double wedge_sine = std::sin(kWedgeKeptDegrees * std::numbers::pi / 180);
  auto meets_face = [&](size_t i, int k, bool low, double d) {
    const double plane = low ? lo[k] : hi[k];
    for (const auto& [x, way] : ReachAlongSheets(
             static_cast<uint32_t>(i), kReachFactor * d / wedge_sine, v, sheets.faces, faces_of)) {
      if (std::abs(sheets.vertices[x][k] - plane) < options.snap_voxels) return true;
    }
    return false;
  };
  for (size_t i = 0; i < v.size(); ++i) {
    bool moved = false;
    for (int k = 0; k < 3; ++k) {
      const double below = v[i][k] - lo[k], above = hi[k] - v[i][k];
      const double d = std::min(below, above);
      double limit = hold[i] ? options.snap_voxels : reach;
      if (d >= options.snap_voxels && d < limit && meets_face(i, k, below < above, d)) {
        limit = options.snap_voxels;
      }
      if (below < limit) {
        moved |= v[i][k] != lo[k];
        wide[i] |= below >= options.snap_voxels;
        v[i][k] = lo[k];
        on_face[i] |= 1 << (2 * k);
      } else if (above < limit) {
        moved |= v[i][k] != hi[k];
        wide[i] |= above >= options.snap_voxels;
        v[i][k] = hi[k];
        on_face[i] |= 1 << (2 * k + 1);
      }
    }
    *snapped += moved;
  }
  return wide;
}

}  // namespace

SnappedSheets SnapToBox(const TriangleMesh& sheets, const Vec3& lo, const Vec3& hi,
                        const PlcOptions& options, PlcStats* stats) {
  SnappedSheets s;
  std::vector<uint8_t> hold(sheets.vertices.size(), 0);  // kept off the box at the wider reach
  for (int round = 0; round < kSnapRounds; ++round) {
    stats->snapped_vertices = stats->merged_vertices = stats->dropped_triangles = 0;
    stats->flipped_edges = stats->dropped_caps = 0;
    stats->snap_held_vertices = static_cast<uint32_t>(std::count(hold.begin(), hold.end(), 1));
    const std::vector<uint8_t> wide =
        SnapVertices(sheets, lo, hi, options, hold, &s, &stats->snapped_vertices);
    s.rep = MergeNearDuplicates(s.v, options.merge_voxels, &s.on_face, &stats->merged_vertices);
    s.st = KeepTriangles(sheets, s.v, s.rep, s.on_face, &stats->dropped_triangles);
    s.held = HeldAtJunctions(s.st, s.v.size());
    if (options.flip_fold_degrees > 0) {
      std::tie(stats->flipped_edges, stats->dropped_caps) = FlipSheetTriangles(
          s.st, s.v, s.on_face, s.held, options.flip_fold_degrees, options.cap_degrees);
    }
    if (round + 1 == kSnapRounds ||
        std::none_of(wide.begin(), wide.end(), [](uint8_t w) { return w; })) {
      break;
    }
    TriangleMesh check;
    check.vertices = s.v;
    check.faces = s.st.faces;
    const auto clash = FindSelfIntersections(check, 1000, 1.0);
    s.checked_clean = clash.empty();
    if (s.checked_clean) break;
    // Hold back the widely snapped vertices (and those merged into them) of the clashing
    // triangles; a clash none of them is in stays, for ResolveClashes to report.
    absl::flat_hash_set<uint32_t> in_clash;
    for (const auto& [a, b] : clash) {
      in_clash.insert(s.st.faces[a].begin(), s.st.faces[a].end());
      in_clash.insert(s.st.faces[b].begin(), s.st.faces[b].end());
    }
    bool held = false;
    for (uint32_t i = 0; i < s.v.size(); ++i) {
      if (wide[i] && in_clash.contains(s.rep[i])) {
        hold[i] = 1;
        held = true;
      }
    }
    if (!held) break;
  }
  return s;
}

}  // namespace sheetmesh
