// The PLC's mends share these: the sheet triangles indexed by vertex, edge and place, the
// way along the sheets from a vertex, and changes applied with the clashes they would make
// left out.
#include <algorithm>
#include <queue>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/mesh/spatial_grid.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/plc_parts.h"

namespace sheetmesh {

SheetIndex IndexSheets(const SheetTriangles& s, const std::vector<Vec3>& v, double grow) {
  SheetIndex index;
  index.faces_of.resize(v.size());
  double longest = grow;
  for (uint32_t f = 0; f < s.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = s.faces[f][k], b = s.faces[f][(k + 1) % 3];
      index.faces_of[a].push_back(f);
      index.edge_faces[EdgeKey(a, b)].push_back(f);
      longest = std::max(longest, Norm(v[a] - v[b]));
    }
  }
  index.grid = SpatialGrid(longest);
  for (uint32_t f = 0; f < s.faces.size(); ++f) {
    Vec3 lo, hi;
    TriangleBox({v[s.faces[f][0]], v[s.faces[f][1]], v[s.faces[f][2]]}, grow, &lo, &hi);
    index.grid.Insert(f, lo, hi);
  }
  return index;
}

uint32_t ApplyLeavingClashesOut(size_t n, const ApplyChanges& apply, SheetTriangles& s,
                                std::vector<Vec3>& v, std::vector<size_t>* left_out) {
  std::vector<size_t> kept(n);
  for (size_t i = 0; i < n; ++i) kept[i] = i;
  for (int attempt = 0; attempt < 6 && !kept.empty(); ++attempt) {
    SheetTriangles out = s;
    std::vector<Vec3> moved = v;
    std::vector<int> owner;
    apply(kept, out, moved, owner);
    TriangleMesh check;
    check.vertices = moved;
    check.faces = out.faces;
    auto clashes = FindSelfIntersections(check, 100000, 1.0);
    // A triangle repeated is a clash too (TetGen aborts on it).
    absl::flat_hash_map<std::array<uint32_t, 3>, uint32_t> seen;
    for (uint32_t f = 0; f < out.faces.size(); ++f) {
      std::array<uint32_t, 3> k = {out.faces[f][0], out.faces[f][1], out.faces[f][2]};
      std::sort(k.begin(), k.end());
      const auto [it, fresh] = seen.try_emplace(k, f);
      if (!fresh) clashes.push_back({it->second, f});
    }
    if (clashes.empty()) {
      s = std::move(out);
      v = std::move(moved);
      return static_cast<uint32_t>(kept.size());
    }
    std::vector<uint8_t> bad(kept.size(), 0);
    bool any = false;
    for (const auto& [f, g] : clashes) {
      for (const uint32_t x : {f, g}) {
        if (owner[x] >= 0) bad[owner[x]] = 1, any = true;
      }
    }
    if (!any) return 0;  // clashes no change made: left to the clash check
    std::vector<size_t> next;
    for (size_t i = 0; i < kept.size(); ++i) {
      if (bad[i]) {
        if (left_out != nullptr) left_out->push_back(kept[i]);
      } else {
        next.push_back(kept[i]);
      }
    }
    kept = std::move(next);
  }
  return 0;
}

std::vector<std::pair<uint32_t, double>> ReachAlongSheets(
    uint32_t u, double limit, const std::vector<Vec3>& v, const std::vector<Face>& faces,
    const std::vector<std::vector<uint32_t>>& faces_of) {
  absl::flat_hash_map<uint32_t, double> done;
  std::vector<std::pair<uint32_t, double>> out;
  using Item = std::pair<double, uint32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  open.push({0.0, u});
  while (!open.empty()) {
    const auto [d, x] = open.top();
    open.pop();
    if (!done.try_emplace(x, d).second) continue;
    out.push_back({x, d});
    for (uint32_t f : faces_of[x]) {
      for (uint32_t y : faces[f]) {
        if (done.contains(y)) continue;
        const double e = d + Norm(v[y] - v[x]);
        if (e <= limit) open.push({e, y});
      }
    }
  }
  return out;
}

}  // namespace sheetmesh
