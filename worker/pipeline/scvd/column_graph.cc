#include "worker/pipeline/scvd/column_graph.h"

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>

#include "absl/strings/str_cat.h"

namespace sheetmesh {
namespace {

constexpr uint32_t kUnset = UINT32_MAX;

// The voxels of the run along axis `axis` (0 x, 1 y, 2 z) that starts at `start`.
void RunAlong(const NeighborTable& nt, uint32_t start, int axis, std::vector<uint32_t>* out) {
  out->clear();
  for (uint32_t v = start; v != kNoNeighbor; v = nt.at(v, 2 * axis + 1)) out->push_back(v);
}

}  // namespace

absl::StatusOr<ColumnGraph> BuildColumnGraph(const VoxelSet& set, const NeighborTable& nt,
                                             uint32_t max_column_voxels) {
  const uint32_t n = static_cast<uint32_t>(set.size());
  // Run lengths along each axis, saturated at 65535.
  std::vector<std::array<uint16_t, 3>> len(n);
  std::vector<uint32_t> run;
  for (int axis = 0; axis < 3; ++axis) {
    for (uint32_t v = 0; v < n; ++v) {
      if (nt.at(v, 2 * axis) != kNoNeighbor) continue;  // not a run start
      RunAlong(nt, v, axis, &run);
      const uint16_t l = static_cast<uint16_t>(std::min<size_t>(run.size(), 65535));
      for (uint32_t w : run) len[w][axis] = l;
    }
  }
  // Thin axis per voxel; z first, then y, then x on ties.
  auto thin = [&](uint32_t v) {
    int best = 2;
    for (int axis : {1, 0}) {
      if (len[v][axis] < len[v][best]) best = axis;
    }
    return best;
  };
  // Each voxel's column: the middle voxel of its run along its thin axis.
  std::vector<uint32_t> rep(n, kUnset);
  for (int axis = 0; axis < 3; ++axis) {
    for (uint32_t v = 0; v < n; ++v) {
      if (nt.at(v, 2 * axis) != kNoNeighbor) continue;
      RunAlong(nt, v, axis, &run);
      if (run.size() > max_column_voxels) continue;
      const uint32_t mid = run[(run.size() - 1) / 2];
      for (uint32_t w : run) {
        if (thin(w) == axis) rep[w] = mid;
      }
    }
  }
  len = {};
  ColumnGraph g;
  std::vector<uint32_t> node_of_rep(n, kUnset);
  for (uint32_t v = 0; v < n; ++v) {
    if (rep[v] == kUnset) rep[v] = v;  // too long to be a column: a node of its own
    node_of_rep[rep[v]] = 0;
  }
  for (uint32_t v = 0; v < n; ++v) {
    if (node_of_rep[v] == kUnset) continue;
    node_of_rep[v] = static_cast<uint32_t>(g.node_voxel.size());
    g.node_voxel.push_back(v);
  }
  g.node_of_voxel.resize(n);
  for (uint32_t v = 0; v < n; ++v) g.node_of_voxel[v] = node_of_rep[rep[v]];
  rep = {};
  if (g.node_voxel.size() >= kUnset) {
    return absl::ResourceExhaustedError(absl::StrCat(g.node_voxel.size(), " columns are too many"));
  }
  // Edges: columns whose voxels touch across a face.
  std::vector<uint64_t> edges;
  for (uint32_t v = 0; v < n; ++v) {
    const uint32_t a = g.node_of_voxel[v];
    for (int k : {1, 3, 5}) {
      const uint32_t u = nt.at(v, k);
      if (u == kNoNeighbor) continue;
      const uint32_t b = g.node_of_voxel[u];
      if (a == b) continue;
      edges.push_back((static_cast<uint64_t>(a) << 32) | b);
      edges.push_back((static_cast<uint64_t>(b) << 32) | a);
    }
  }
  tbb::parallel_sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  g.graph.offsets.assign(g.node_voxel.size() + 1, 0);
  g.graph.targets.resize(edges.size());
  for (size_t i = 0; i < edges.size(); ++i) {
    ++g.graph.offsets[(edges[i] >> 32) + 1];
    g.graph.targets[i] = static_cast<uint32_t>(edges[i] & 0xFFFFFFFFu);
  }
  for (size_t i = 1; i < g.graph.offsets.size(); ++i) g.graph.offsets[i] += g.graph.offsets[i - 1];
  return g;
}

}  // namespace sheetmesh
