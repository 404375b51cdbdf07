#include "worker/pipeline/scvd/column_graph.h"

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <bit>

#include "absl/container/flat_hash_map.h"
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
                                             uint32_t max_column_voxels, uint32_t vote_block,
                                             const Index3& origin) {
  const uint32_t n = static_cast<uint32_t>(set.size());
  // Thin axis per voxel: its shortest run (lengths saturated at 65535); z first, then y,
  // then x on ties. One axis at a time, so only the shortest length so far is held.
  std::vector<uint8_t> thin(n, 2);
  {
    std::vector<uint16_t> shortest(n, 0);
    std::vector<uint32_t> run;
    for (int axis : {2, 1, 0}) {
      for (uint32_t v = 0; v < n; ++v) {
        if (nt.at(v, 2 * axis) != kNoNeighbor) continue;  // not a run start
        RunAlong(nt, v, axis, &run);
        const uint16_t l = static_cast<uint16_t>(std::min<size_t>(run.size(), 65535));
        for (uint32_t w : run) {
          if (axis == 2 || l < shortest[w]) {
            shortest[w] = l;
            thin[w] = static_cast<uint8_t>(axis);
          }
        }
      }
    }
  }
  // The shortest run is not always across the sheet: where a thick tilted sheet meets its
  // own rim, runs along the sheet are cut short in a wedge and would cross the columns of
  // their neighbours (stacked cells, folded triangles). So the axis is voted for in blocks
  // about a thickness wide: every voxel takes the majority of its block and
  // the 26 around it (its own vote on ties),
  // and a column is a run its neighbourhood agrees is the thickness.
  if (vote_block > 1) {
    const Dims& d = set.dims();
    // Blocks on the global grid: block b of the set is global block b + first.
    const int64_t first_x = origin.x / vote_block, first_y = origin.y / vote_block,
                  first_z = origin.z / vote_block;
    const int64_t nbx = d.nx / vote_block + 4, nby = d.ny / vote_block + 4;
    // Blocks are numbered with a margin of one, so the 27 around any block exist.
    auto block_of = [&](int64_t bx, int64_t by, int64_t bz) {
      return static_cast<uint64_t>(((bz + 1) * nby + by + 1) * nbx + bx + 1);
    };
    auto block_of_voxel = [&](int32_t x, int32_t y, int32_t z) {
      return block_of((x + origin.x) / vote_block - first_x, (y + origin.y) / vote_block - first_y,
                      (z + origin.z) / vote_block - first_z);
    };
    absl::flat_hash_map<uint64_t, std::array<uint32_t, 3>> own, votes;
    set.ForEachVoxel([&](uint64_t v, int32_t x, int32_t y, int32_t z) {
      ++own[block_of_voxel(x, y, z)][thin[v]];
    });
    // Each block's vote: its own and its 26 neighbours' voxels.
    for (const auto& [key, count] : own) {
      const int64_t bx = static_cast<int64_t>(key % nbx) - 1;
      const int64_t by = static_cast<int64_t>(key / nbx % nby) - 1;
      const int64_t bz = static_cast<int64_t>(key / nbx / nby) - 1;
      std::array<uint32_t, 3>& sum = votes[key];
      for (int64_t dz = -1; dz <= 1; ++dz)
        for (int64_t dy = -1; dy <= 1; ++dy)
          for (int64_t dx = -1; dx <= 1; ++dx) {
            const auto it = own.find(block_of(bx + dx, by + dy, bz + dz));
            if (it == own.end()) continue;
            for (int a = 0; a < 3; ++a) sum[a] += it->second[a];
          }
    }
    own = {};
    set.ForEachVoxel([&](uint64_t v, int32_t x, int32_t y, int32_t z) {
      const std::array<uint32_t, 3>& c = votes.at(block_of_voxel(x, y, z));
      int best = thin[v];
      for (int axis : {2, 1, 0}) {
        if (c[axis] > c[best]) best = axis;
      }
      thin[v] = static_cast<uint8_t>(best);
    });
  }
  // Each voxel's column: the middle voxel of its run along its thin axis.
  std::vector<uint32_t> rep(n, kUnset);
  std::vector<uint32_t> run;
  for (int axis = 0; axis < 3; ++axis) {
    for (uint32_t v = 0; v < n; ++v) {
      if (nt.at(v, 2 * axis) != kNoNeighbor) continue;
      RunAlong(nt, v, axis, &run);
      if (run.size() > max_column_voxels) continue;
      const uint32_t mid = run[(run.size() - 1) / 2];
      for (uint32_t w : run) {
        if (thin[w] == axis) rep[w] = mid;
      }
    }
  }
  thin = {};
  // Nodes are the representatives in ascending order: a node's number is how many
  // representatives come before it (a bit per voxel and a count per 64 of them), written
  // over `rep` in place, which becomes node_of_voxel.
  ColumnGraph g;
  std::vector<uint64_t> is_rep((n + 63) / 64, 0);
  for (uint32_t v = 0; v < n; ++v) {
    if (rep[v] == kUnset) rep[v] = v;  // too long to be a column: a node of its own
    is_rep[rep[v] / 64] |= uint64_t{1} << (rep[v] % 64);
  }
  std::vector<uint32_t> before(is_rep.size());
  uint64_t nodes = 0;
  for (size_t w = 0; w < is_rep.size(); ++w) {
    before[w] = static_cast<uint32_t>(std::min<uint64_t>(nodes, kUnset));
    nodes += static_cast<uint64_t>(std::popcount(is_rep[w]));
  }
  if (nodes >= kUnset) {
    return absl::ResourceExhaustedError(absl::StrCat(nodes, " columns are too many"));
  }
  g.node_voxel.reserve(nodes);
  for (size_t w = 0; w < is_rep.size(); ++w) {
    for (uint64_t bits = is_rep[w]; bits != 0; bits &= bits - 1) {
      g.node_voxel.push_back(static_cast<uint32_t>(w * 64 + std::countr_zero(bits)));
    }
  }
  for (uint32_t v = 0; v < n; ++v) {
    const uint32_t r = rep[v];
    const uint64_t below = is_rep[r / 64] & ((uint64_t{1} << (r % 64)) - 1);
    rep[v] = before[r / 64] + static_cast<uint32_t>(std::popcount(below));
  }
  is_rep = {};
  before = {};
  g.node_of_voxel = std::move(rep);
  // Edges: columns whose voxels touch across a face, each once as (lower, higher). A
  // column's voxels name the same neighbours over and over, so the edges are gathered in
  // chunks, each reduced and merged as it fills: what is held follows the columns' edges,
  // not the voxels' faces (at 2048³ that list was gigabytes).
  std::vector<uint64_t> edges, chunk;
  constexpr size_t kChunk = size_t{1} << 22;
  chunk.reserve(kChunk);
  const auto flush = [&] {
    tbb::parallel_sort(chunk.begin(), chunk.end());
    chunk.erase(std::unique(chunk.begin(), chunk.end()), chunk.end());
    const size_t old_size = edges.size();
    edges.insert(edges.end(), chunk.begin(), chunk.end());
    std::inplace_merge(edges.begin(), edges.begin() + old_size, edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    chunk.clear();
  };
  for (uint32_t v = 0; v < n; ++v) {
    const uint32_t a = g.node_of_voxel[v];
    for (int k : {1, 3, 5}) {
      const uint32_t u = nt.at(v, k);
      if (u == kNoNeighbor) continue;
      const uint32_t b = g.node_of_voxel[u];
      if (a == b) continue;
      chunk.push_back((static_cast<uint64_t>(std::min(a, b)) << 32) | std::max(a, b));
      if (chunk.size() == kChunk) flush();
    }
  }
  flush();
  chunk = {};
  // Each edge in both nodes' rows; sorted (lower, higher), so every row comes out ascending.
  g.graph.offsets.assign(g.node_voxel.size() + 1, 0);
  for (const uint64_t e : edges) {
    ++g.graph.offsets[(e >> 32) + 1];
    ++g.graph.offsets[(e & 0xFFFFFFFFu) + 1];
  }
  for (size_t i = 1; i < g.graph.offsets.size(); ++i) g.graph.offsets[i] += g.graph.offsets[i - 1];
  g.graph.targets.resize(2 * edges.size());
  std::vector<uint64_t> fill(g.graph.offsets.begin(), g.graph.offsets.end() - 1);
  for (const uint64_t e : edges) {
    const uint32_t a = static_cast<uint32_t>(e >> 32), b = static_cast<uint32_t>(e & 0xFFFFFFFFu);
    g.graph.targets[fill[a]++] = b;
    g.graph.targets[fill[b]++] = a;
  }
  return g;
}

}  // namespace sheetmesh
