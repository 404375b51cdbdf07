// Generators chosen so that a brick of the volume with a halo chooses, near its core, the
// same ones as the whole volume: each node decides by a hash of its voxel's position in
// the whole volume and of the nodes near it, not by its place in one random stream over
// the set (issue 47's bricks). Formula 3 holds in expectation instead of exactly per
// component.
#ifndef SHEETMESH_WORKER_PIPELINE_SCVD_LOCAL_SEEDS_H_
#define SHEETMESH_WORKER_PIPELINE_SCVD_LOCAL_SEEDS_H_

#include <algorithm>
#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "common/types.h"

namespace sheetmesh {

// Uniform in [0, 1): a hash of the global voxel position `p` and `seed` (SplitMix64's
// finaliser over the packed coordinates), the same on every machine.
double PositionHash(const Index3& p, uint64_t seed);

// How generators are drawn.
struct LocalDraw {
  // The expected generators per voxel: 1 / V_vol (formula 3), or generator_count / voxels.
  double per_voxel = 0;
  // 0: each node is a generator where its hash is below its voxels times per_voxel
  // (Bernoulli: a piece's count spreads like Poisson's). > 0: stratified on a global grid
  // of cubes of side 2 spacing — a cube whose nodes stand for W voxels gets
  // floor(W per_voxel + u) generators, u a hash of the cube and the seed (so W per_voxel in
  // expectation, exactly, with a spread of at most one), placed at its nodes of least hash
  // that lie `spacing` apart where it has such (Euclidean, global positions). With spacing
  // = ExclusionRadius, a cube crossed by a sheet holds one or two cells' voxels.
  double spacing = 0;
  uint64_t seed = 1;
};

// The radius of a ball, centred in a sheet of `thickness` voxels, whose part in the sheet
// holds `voxels` voxels (a slab's cut of the ball: π (R² t − t³ / 12), or the whole ball where
// it fits in the slab); over columns (nodes standing for a column of the sheet's thickness
// each) the disc of voxels / thickness nodes.
double ExclusionRadius(double voxels, double thickness, bool columns);

struct LocalSeeds {
  std::vector<uint32_t> nodes;      // ascending: ids follow the nodes' (z, y, x) order
  std::vector<uint32_t> component;  // the component of each
};

// The stratified draw (LocalDraw::spacing > 0) over the nodes `for_each_node(f)` visits as
// f(n, global position, voxels it stands for), twice, in ascending n; ascending nodes.
std::vector<uint32_t> StratifiedDraw(
    const LocalDraw& draw,
    const std::function<void(const std::function<void(uint32_t, const Index3&, double)>&)>&
        for_each_node);

// Chooses generators among the nodes as `draw` says (node_voxels[n]: the voxels
// node n stands for; empty: one each), and a component (`node_component`, labels below
// `num_components`) left with none gets its node of least hash. `for_each_node(f)` calls
// f(n, global position of node n) for every node in ascending n. Deterministic; a node's
// choice depends on the nodes of its cube of the draw's grid (or on it alone), the
// fallback on its component within the set.
template <class ForEachNode>
LocalSeeds ChooseLocalSeeds(std::span<const uint32_t> node_voxels,
                            std::span<const uint32_t> node_component, uint32_t num_components,
                            const LocalDraw& draw, const ForEachNode& for_each_node) {
  LocalSeeds out;
  std::vector<double> least(num_components, 2.0);
  std::vector<uint32_t> least_node(num_components, UINT32_MAX);
  auto voxels_of = [&](uint32_t n) { return node_voxels.empty() ? 1.0 : double(node_voxels[n]); };
  for_each_node([&](uint32_t n, const Index3& p) {
    const double h = PositionHash(p, draw.seed);
    const uint32_t c = node_component[n];
    if (draw.spacing <= 0 && h < voxels_of(n) * draw.per_voxel) out.nodes.push_back(n);
    if (h < least[c]) {
      least[c] = h;
      least_node[c] = n;
    }
  });
  if (draw.spacing > 0) {
    out.nodes = StratifiedDraw(draw, [&](const auto& f) {
      for_each_node([&](uint32_t n, const Index3& p) { f(n, p, voxels_of(n)); });
    });
  }
  std::vector<uint8_t> chosen_in(num_components, 0);
  for (uint32_t n : out.nodes) chosen_in[node_component[n]] = 1;
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
