// Local refinement of the PLC's sheet triangles where the volume mesh kept slivers: a
// tetrahedron whose corners all lie on the sheets (two layers of a sheet nearly touching at
// a fold, a rim running just over another sheet) is as flat as the gap between them is
// narrow against the sheet edges that pin it; nothing that moves or adds points off the
// sheets can mend it, but halving those edges doubles its angles.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "worker/pipeline/tet/plc.h"

namespace sheetmesh {
namespace {

// Whether the segment a-b lies in one of the box's faces (such an edge is a segment of that
// face's facet too, which a split would have to follow).
bool OnBoxFace(const Vec3& a, const Vec3& b, const Vec3& lo, const Vec3& hi) {
  const double tol = 1e-9 * (1 + Norm(hi - lo));
  for (int k = 0; k < 3; ++k) {
    for (const double side : {lo[k], hi[k]}) {
      if (std::abs(a[k] - side) <= tol && std::abs(b[k] - side) <= tol) return true;
    }
  }
  return false;
}

}  // namespace

uint32_t RefineSheetTriangles(const std::vector<uint8_t>& marked, Plc* plc) {
  std::vector<Face>& tris = plc->sheet_triangles;
  const size_t first_sheet_facet = plc->facets.size() - tris.size();
  // Each edge's triangles, kept up to date as they split.
  absl::flat_hash_map<uint64_t, std::vector<uint32_t>> faces_of;
  auto link = [&](uint32_t t, bool add) {
    for (int k = 0; k < 3; ++k) {
      std::vector<uint32_t>& on = faces_of[EdgeKey(tris[t][k], tris[t][(k + 1) % 3])];
      if (add) {
        on.push_back(t);
      } else {
        on.erase(std::remove(on.begin(), on.end(), t), on.end());
      }
    }
  };
  for (uint32_t t = 0; t < tris.size(); ++t) link(t, true);
  // The marked triangles' edges, off the box's faces, in a fixed order.
  std::vector<std::pair<uint32_t, uint32_t>> edges;
  for (uint32_t t = 0; t < std::min(marked.size(), tris.size()); ++t) {
    if (!marked[t]) continue;
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tris[t][k], b = tris[t][(k + 1) % 3];
      if (OnBoxFace(plc->vertices[a], plc->vertices[b], plc->box_lo, plc->box_hi)) continue;
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  uint32_t split = 0;
  for (const auto& [a, b] : edges) {
    const std::vector<uint32_t> on_edge = faces_of[EdgeKey(a, b)];
    if (on_edge.empty()) continue;
    const uint32_t m = static_cast<uint32_t>(plc->vertices.size());
    plc->vertices.push_back((plc->vertices[a] + plc->vertices[b]) * 0.5);
    for (const uint32_t f : on_edge) {
      // (.. a .. b ..) -> (.. a .. m ..) and (.. m .. b ..): the same orientation.
      const Face g = tris[f];
      const int ia = g[0] == a ? 0 : g[1] == a ? 1 : 2;
      const int ib = g[0] == b ? 0 : g[1] == b ? 1 : 2;
      Face first = g, second = g;
      first[ib] = m;
      second[ia] = m;
      link(f, false);
      tris[f] = first;
      plc->facets[first_sheet_facet + f].polygons = {{first[0], first[1], first[2]}};
      link(f, true);
      const uint32_t added = static_cast<uint32_t>(tris.size());
      tris.push_back(second);
      plc->sheet_piece.push_back(plc->sheet_piece[f]);
      plc->sheet_thickness.push_back(plc->sheet_thickness[f]);
      plc->facets.push_back(
          {{{second[0], second[1], second[2]}}, kFirstSheetMarker + static_cast<int32_t>(added)});
      link(added, true);
    }
    ++split;
  }
  return split;
}

uint32_t DropSheetTriangles(const std::vector<uint8_t>& drop, Plc* plc) {
  const size_t first_sheet_facet = plc->facets.size() - plc->sheet_triangles.size();
  Plc kept_only = *plc;
  kept_only.facets.resize(first_sheet_facet);
  kept_only.sheet_triangles.clear();
  kept_only.sheet_piece.clear();
  kept_only.sheet_thickness.clear();
  uint32_t dropped = 0;
  for (size_t t = 0; t < plc->sheet_triangles.size(); ++t) {
    if (t < drop.size() && drop[t]) {
      ++dropped;
      continue;
    }
    const Face& f = plc->sheet_triangles[t];
    kept_only.facets.push_back(
        {{{f[0], f[1], f[2]}},
         kFirstSheetMarker + static_cast<int32_t>(kept_only.sheet_triangles.size())});
    kept_only.sheet_triangles.push_back(f);
    kept_only.sheet_piece.push_back(plc->sheet_piece[t]);
    kept_only.sheet_thickness.push_back(plc->sheet_thickness[t]);
  }
  *plc = std::move(kept_only);
  return dropped;
}

}  // namespace sheetmesh
