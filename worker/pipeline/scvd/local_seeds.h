// Generators chosen so that a brick of the volume with a halo chooses, near its core, the
// same ones as the whole volume: each node decides by a hash of its voxel's position in
// the whole volume, not by its place in one random stream over the set (issue 47's
// bricks). Formula 3 holds in expectation instead of exactly per component.
#ifndef SHEETMESH_WORKER_PIPELINE_SCVD_LOCAL_SEEDS_H_
#define SHEETMESH_WORKER_PIPELINE_SCVD_LOCAL_SEEDS_H_

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "common/types.h"

namespace sheetmesh {

// Uniform in [0, 1): a hash of the global voxel position `p` and `seed` (SplitMix64's
// finaliser over the packed coordinates), the same on every machine.
double PositionHash(const Index3& p, uint64_t seed);

struct LocalSeeds {
  std::vector<uint32_t> nodes;      // ascending: ids follow the nodes' (z, y, x) order
  std::vector<uint32_t> component;  // the component of each
};

// Chooses generators among `num_nodes` nodes: node n is one when
// PositionHash(global position of its voxel, seed) < node_voxels[n] * per_voxel (formula 3
// in expectation: per_voxel = 1 / V_vol), and a component (`node_component`, labels
// below `num_components`) no hash chose gets its node of least hash; node_voxels empty:
// one voxel each. `for_each_node(f)` calls f(n, global position of node n) for every node
// in ascending n. Deterministic; a node's choice depends on it alone, the fallback on its
// component within the set.
template <class ForEachNode>
LocalSeeds ChooseLocalSeeds(std::span<const uint32_t> node_voxels,
                            std::span<const uint32_t> node_component, uint32_t num_components,
                            double per_voxel, uint64_t seed, const ForEachNode& for_each_node) {
  LocalSeeds out;
  std::vector<double> least(num_components, 2.0);
  std::vector<uint32_t> least_node(num_components, UINT32_MAX);
  std::vector<uint8_t> chosen_in(num_components, 0);
  for_each_node([&](uint32_t n, const Index3& p) {
    const double h = PositionHash(p, seed);
    const uint32_t c = node_component[n];
    const double voxels = node_voxels.empty() ? 1.0 : double(node_voxels[n]);
    if (h < voxels * per_voxel) {
      out.nodes.push_back(n);
      chosen_in[c] = 1;
    }
    if (h < least[c]) {
      least[c] = h;
      least_node[c] = n;
    }
  });
  std::vector<uint32_t> fallback;
  for (uint32_t c = 0; c < num_components; ++c) {
    if (!chosen_in[c] && least_node[c] != UINT32_MAX) fallback.push_back(least_node[c]);
  }
  if (!fallback.empty()) {
    std::sort(fallback.begin(), fallback.end());
    std::vector<uint32_t> merged(out.nodes.size() + fallback.size());
    std::merge(out.nodes.begin(), out.nodes.end(), fallback.begin(), fallback.end(),
               merged.begin());
    out.nodes.swap(merged);
  }
  out.component.reserve(out.nodes.size());
  for (uint32_t n : out.nodes) out.component.push_back(node_component[n]);
  return out;
}

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SCVD_LOCAL_SEEDS_H_
