#include "worker/pipeline/scvd/scvd.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"
#include "common/random.h"
#include "common/status_macros.h"
#include "worker/pipeline/scvd/column_graph.h"
#include "worker/pipeline/scvd/local_seeds.h"

namespace sheetmesh {

double CellVolume(double mean_thickness, double radius) {
  // Formula 3: a BFS (L1) disc of radius r - 1 has 1 + 2 r (r - 1) voxels per layer.
  return mean_thickness * (1.0 + 2.0 * radius * (radius - 1.0));
}

int64_t GeneratorsForComponent(uint64_t voxels, double cell_volume) {
  return std::max<int64_t>(1, std::llround(static_cast<double>(voxels) / cell_volume));
}

namespace {

// Synchronous multi-source breadth-first growth over `num_nodes` nodes whose neighbours
// `for_each_neighbor(v, f)` visits. A node joins the first cell to reach it; among cells
// reaching it in the same round, the lowest id — so the result does not depend on the
// order of the frontier, and each round runs on all cores. A node's round and cell share
// one word (round << 32 | cell; round 0: not reached), so a look-up touches one place:
// the one thread that moves it from 0 claims it for the round, and a lower cell offered in
// the same round replaces the one there (relaxed atomics; the round's end orders them).
template <class ForEachNeighbor>
absl::StatusOr<std::vector<uint32_t>> Grow(size_t num_nodes, ForEachNeighbor for_each_neighbor,
                                           std::span<const uint32_t> seeds,
                                           const Progress& progress) {
  constexpr uint64_t kSeedRound = std::numeric_limits<uint32_t>::max();
  auto word = [](uint64_t round, uint32_t cell) { return round << 32 | cell; };
  std::vector<uint64_t> state(num_nodes, 0);
  std::vector<uint32_t> frontier;
  frontier.reserve(seeds.size());
  for (size_t i = 0; i < seeds.size(); ++i) {
    state[seeds[i]] = word(kSeedRound, static_cast<uint32_t>(i));
    frontier.push_back(seeds[i]);
  }
  tbb::enumerable_thread_specific<std::vector<uint32_t>> claimed;
  uint64_t r = 0;
  size_t reached = frontier.size();
  while (!frontier.empty()) {
    ++r;
    for (auto& c : claimed) c.clear();
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, frontier.size(), 4096),
        [&](const tbb::blocked_range<size_t>& range) {
          std::vector<uint32_t>& mine = claimed.local();
          for (size_t i = range.begin(); i != range.end(); ++i) {
            const uint32_t v = frontier[i];
            // Set in an earlier round: only read in this one.
            const uint64_t offer = word(r, static_cast<uint32_t>(state[v]));
            for_each_neighbor(v, [&](uint32_t u) {
              std::atomic_ref<uint64_t> su(state[u]);
              uint64_t now = su.load(std::memory_order_relaxed);
              if (now == 0) {
                if (su.compare_exchange_strong(now, offer, std::memory_order_relaxed)) {
                  mine.push_back(u);
                  return;
                }
              }
              // Reached this round by another cell: the lower id stays.
              while (now >> 32 == r && offer < now &&
                     !su.compare_exchange_weak(now, offer, std::memory_order_relaxed)) {
              }
            });
          }
        });
    frontier.clear();
    for (const auto& c : claimed) frontier.insert(frontier.end(), c.begin(), c.end());
    reached += frontier.size();
    if ((r & 15) == 0) {
      SM_RETURN_IF_ERROR(progress.Update(double(reached) / std::max<size_t>(1, num_nodes)));
    }
  }
  std::vector<uint32_t> cell(num_nodes);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, num_nodes, 1 << 16),
                    [&](const tbb::blocked_range<size_t>& range) {
                      for (size_t v = range.begin(); v != range.end(); ++v) {
                        cell[v] = state[v] == 0 ? kNoCell : static_cast<uint32_t>(state[v]);
                      }
                    });
  return cell;
}

}  // namespace

absl::StatusOr<std::vector<uint32_t>> GrowCells(const NeighborTable& neighbors,
                                                std::span<const uint32_t> seeds,
                                                const Progress& progress) {
  return Grow(
      neighbors.size(),
      [&](uint32_t v, auto&& f) {
        for (uint32_t u : neighbors.of(v)) {
          if (u != kNoNeighbor) f(u);
        }
      },
      seeds, progress);
}

absl::StatusOr<std::vector<uint32_t>> GrowCells(const CsrGraph& graph,
                                                std::span<const uint32_t> seeds,
                                                const Progress& progress) {
  return Grow(
      graph.num_nodes(),
      [&](uint32_t v, auto&& f) {
        for (uint32_t u : graph.of(v)) f(u);
      },
      seeds, progress);
}

std::vector<std::pair<uint32_t, uint32_t>> CellAdjacency(const NeighborTable& neighbors,
                                                         std::span<const uint32_t> cell) {
  std::vector<std::pair<uint32_t, uint32_t>> pairs;
  for (uint32_t v = 0; v < neighbors.size(); ++v) {
    const uint32_t a = cell[v];
    if (a == kNoCell) continue;
    for (int k : {1, 3, 5}) {  // each face once: the + directions
      const uint32_t u = neighbors.at(v, k);
      if (u == kNoNeighbor) continue;
      const uint32_t b = cell[u];
      if (b != a && b != kNoCell) pairs.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  tbb::parallel_sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

namespace {

absl::Status Validate(const VoxelSet& set, double thickness, const ScvdOptions& o) {
  if (!(o.radius_voxels > 0) || !std::isfinite(o.radius_voxels)) {
    return absl::InvalidArgumentError(
        absl::StrCat("SCVD radius r = ", o.radius_voxels, " voxels must be positive"));
  }
  if (!(thickness > 0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("SCVD mean thickness ", thickness, " voxels must be positive"));
  }
  if (set.empty()) return absl::InvalidArgumentError("SCVD of an empty sheet phase");
  if (!o.density.empty()) {
    if (o.density.size() != set.size()) {
      return absl::InvalidArgumentError(absl::StrCat("SCVD density has ", o.density.size(),
                                                     " values for ", set.size(), " voxels"));
    }
    for (float rho : o.density) {
      if (!(rho > 0) || !std::isfinite(rho)) {
        return absl::InvalidArgumentError(
            absl::StrCat("SCVD density ", rho, " must be positive and finite"));
      }
    }
  }
  if (o.lloyd_max_iter < 0 || !(o.lloyd_tol >= 0)) {
    return absl::InvalidArgumentError(absl::StrCat("SCVD lloyd_max_iter ", o.lloyd_max_iter,
                                                   " and lloyd_tol ", o.lloyd_tol,
                                                   " must not be negative"));
  }
  if (o.origin.x < 0 || o.origin.y < 0 || o.origin.z < 0) {
    return absl::InvalidArgumentError(absl::StrCat("SCVD origin (", o.origin.x, ", ", o.origin.y,
                                                   ", ", o.origin.z, ") must not be negative"));
  }
  if ((o.local || !o.generators.empty()) && !o.density.empty()) {
    return absl::InvalidArgumentError(
        "SCVD local seeding with a density is not supported (a density's scale is global)");
  }
  const Dims& d = set.dims();
  const double box = static_cast<double>(std::max({d.nx, d.ny, d.nz}));
  if (o.radius_voxels > 2 * box) {
    return absl::InvalidArgumentError(absl::StrCat("SCVD radius r = ", o.radius_voxels,
                                                   " voxels exceeds twice the volume's largest "
                                                   "extent (",
                                                   box, ")"));
  }
  return absl::OkStatus();
}

// Calls f(node, x, y, z) for every node in node order: the set's voxels in index order (no
// array of coordinates: at 2048³ that would be 1 GB), or the columns' voxels.
class NodeCoordinates {
 public:
  // Coordinates are the set's plus `origin`.
  NodeCoordinates(const VoxelSet& set, const ColumnGraph* columns, const Index3& origin)
      : set_(set), columns_(columns != nullptr), o_(origin) {
    if (!columns_) return;
    xyz_.resize(columns->num_nodes());
    for (uint32_t n = 0; n < xyz_.size(); ++n) xyz_[n] = set.CoordOf(columns->node_voxel[n]);
  }
  template <class F>
  void ForEach(F&& f) const {
    if (!columns_) {
      set_.ForEachVoxel([&](uint64_t v, int32_t x, int32_t y, int32_t z) {
        f(static_cast<uint32_t>(v), x + o_.x, y + o_.y, z + o_.z);
      });
      return;
    }
    for (uint32_t n = 0; n < xyz_.size(); ++n) {
      f(n, xyz_[n].x + o_.x, xyz_[n].y + o_.y, xyz_[n].z + o_.z);
    }
  }

 private:
  const VoxelSet& set_;
  const bool columns_;
  const Index3 o_;
  std::vector<Index3> xyz_;  // with columns: each node's voxel
};

// Per cell sums for centroids and the energy against the current generators (formula 2:
// every voxel weighs its density ρ, 1 without one).
struct CellStats {
  std::vector<Vec3> sum;        // Σ ρ x
  std::vector<double> weight;   // Σ ρ
  std::vector<uint32_t> count;  // voxels
  double energy = 0;

  Vec3 Centroid(uint32_t c) const { return sum[c] / weight[c]; }
};

// Sums in global coordinates (the set's plus `origin`), so a brick's cells sum as the
// whole's do, to the last bit.
CellStats Accumulate(const VoxelSet& set, const Index3& origin, const std::vector<uint32_t>& cell,
                     const std::vector<Index3>& generators, std::span<const float> density) {
  CellStats s;
  s.sum.assign(generators.size(), Vec3());
  s.weight.assign(generators.size(), 0.0);
  s.count.assign(generators.size(), 0);
  set.ForEachVoxel([&](uint64_t v, int32_t x, int32_t y, int32_t z) {
    const uint32_t c = cell[v];
    if (c == kNoCell) return;
    x += origin.x, y += origin.y, z += origin.z;
    const double rho = density.empty() ? 1.0 : density[v];
    s.sum[c] += Vec3(x, y, z) * rho;
    s.weight[c] += rho;
    ++s.count[c];
    const double dx = x - origin.x - generators[c].x, dy = y - origin.y - generators[c].y,
                 dz = z - origin.z - generators[c].z;
    s.energy += rho * (dx * dx + dy * dy + dz * dz);
  });
  return s;
}

// Seeds: n_c distinct nodes per component (formula 3 on its voxel count), drawn by a
// partial Fisher-Yates shuffle over the component's nodes (grouped by a counting sort of
// the labels). Records each generator's component in scvd. kResourceExhausted when there
// would be too many.
template <class VoxelOf>
absl::StatusOr<std::vector<uint32_t>> SeedGenerators(const VoxelSet& set,
                                                     const Components& components,
                                                     uint32_t num_nodes, const VoxelOf& voxel_of,
                                                     const ScvdOptions& options, Scvd* scvd) {
  const uint32_t num_components = components.count();
  const std::vector<uint32_t> label = components.VoxelLabels(set);
  std::vector<uint32_t> node_label(num_nodes);
  for (uint32_t n = 0; n < num_nodes; ++n) node_label[n] = label[voxel_of(n)];
  std::vector<uint64_t> start(num_components + 1, 0);
  for (uint32_t l : node_label) ++start[l + 1];
  for (uint32_t c = 0; c < num_components; ++c) start[c + 1] += start[c];
  std::vector<uint32_t> members(num_nodes);
  {
    std::vector<uint64_t> fill(start.begin(), start.end() - 1);
    for (uint32_t n = 0; n < num_nodes; ++n) members[fill[node_label[n]]++] = n;
  }
  Rng rng(options.seed);
  std::vector<uint32_t> seeds;
  for (uint32_t c = 0; c < num_components; ++c) {
    const uint64_t size = components.sizes[c];
    const uint64_t nodes = start[c + 1] - start[c];
    int64_t n = options.generator_count > 0
                    ? std::max<int64_t>(1, std::llround(double(options.generator_count) * size /
                                                        double(set.size())))
                    : GeneratorsForComponent(size, scvd->cell_volume);
    n = std::min<int64_t>(n, static_cast<int64_t>(nodes));
    uint32_t* m = members.data() + start[c];
    if (options.density.empty()) {
      for (int64_t k = 0; k < n; ++k) {
        const uint64_t j = k + rng.Below(nodes - k);
        std::swap(m[k], m[j]);
        seeds.push_back(m[k]);
        scvd->generator_component.push_back(c);
      }
      continue;
    }
    // With a density, a node is kept with probability sqrt(ρ / ρ_max) as the shuffle
    // reaches it (a planar CVT's cells are as dense as sqrt ρ), the rest in shuffle order
    // if too few are kept.
    float most = 0;
    for (uint64_t k = 0; k < nodes; ++k) most = std::max(most, options.density[voxel_of(m[k])]);
    uint64_t kept = 0;
    for (uint64_t k = 0; k < nodes && kept < static_cast<uint64_t>(n); ++k) {
      const uint64_t j = k + rng.Below(nodes - k);
      std::swap(m[k], m[j]);
      if (rng.Uniform() * most < std::sqrt(options.density[voxel_of(m[k])] * most)) {
        std::swap(m[kept++], m[k]);
      }
    }
    for (uint64_t k = 0; k < static_cast<uint64_t>(n); ++k) {
      seeds.push_back(m[k]);
      scvd->generator_component.push_back(c);
    }
  }
  if (seeds.size() >= kNoCell) {
    return absl::ResourceExhaustedError(absl::StrCat(seeds.size(), " generators are too many"));
  }
  return seeds;
}

// Local seeds (local_seeds.h) over the voxels or the columns; records each generator's
// component in scvd.
absl::StatusOr<std::vector<uint32_t>> SeedLocally(const VoxelSet& set, const Components& components,
                                                  uint32_t num_nodes, const ColumnGraph* columns,
                                                  const ScvdOptions& options, Scvd* scvd) {
  const std::vector<uint32_t> label = components.VoxelLabels(set);
  std::vector<uint32_t> node_label, node_voxels;
  if (columns != nullptr) {
    node_label.resize(num_nodes);
    node_voxels.assign(num_nodes, 0);
    for (uint32_t n = 0; n < num_nodes; ++n) node_label[n] = label[columns->node_voxel[n]];
    for (uint32_t node : columns->node_of_voxel) ++node_voxels[node];
  }
  LocalDraw draw;
  draw.per_voxel = options.generator_count > 0
                       ? double(options.generator_count) / double(set.size())
                       : 1.0 / scvd->cell_volume;
  draw.seed = options.seed;
  if (options.local_spacing) {
    draw.spacing = ExclusionRadius(1.0 / draw.per_voxel, scvd->mean_thickness, columns != nullptr);
  }
  const Index3 o = options.origin;
  auto for_each_node = [&](auto&& f) {
    set.ForEachVoxel([&](uint64_t v, int32_t x, int32_t y, int32_t z) {
      const auto n = static_cast<uint32_t>(columns != nullptr ? columns->node_of_voxel[v] : v);
      if (columns == nullptr || columns->node_voxel[n] == v)
        f(n, Index3{x + o.x, y + o.y, z + o.z});
    });
  };
  LocalSeeds chosen = ChooseLocalSeeds(node_voxels, columns != nullptr ? node_label : label,
                                       components.count(), draw, for_each_node);
  if (chosen.nodes.size() >= kNoCell) {
    return absl::ResourceExhaustedError(
        absl::StrCat(chosen.nodes.size(), " generators are too many"));
  }
  scvd->generator_component = std::move(chosen.component);
  return std::move(chosen.nodes);
}

// The nodes of the given generators (options.generators), ascending, each once; records
// each generator's component in scvd.
std::vector<uint32_t> GivenSeeds(const VoxelSet& set, const Components& components,
                                 const ColumnGraph* columns, const ScvdOptions& options,
                                 Scvd* scvd) {
  const Index3 o = options.origin;
  std::vector<std::pair<uint32_t, uint32_t>> node_voxel;  // (node, voxel)
  for (const Index3& p : options.generators) {
    const int64_t v = set.Find(p.x - o.x, p.y - o.y, p.z - o.z);
    if (v < 0) continue;
    const auto voxel = static_cast<uint32_t>(v);
    node_voxel.emplace_back(columns != nullptr ? columns->node_of_voxel[voxel] : voxel, voxel);
  }
  std::sort(node_voxel.begin(), node_voxel.end());
  node_voxel.erase(std::unique(node_voxel.begin(), node_voxel.end(),
                               [](const auto& a, const auto& b) { return a.first == b.first; }),
                   node_voxel.end());
  const std::vector<uint32_t> label = components.VoxelLabels(set);
  std::vector<uint32_t> seeds;
  for (const auto& [node, voxel] : node_voxel) {
    seeds.push_back(node);
    scvd->generator_component.push_back(label[voxel]);
  }
  return seeds;
}

// Each cell's node nearest to its centroid (ties to the lower node, so the result does not
// depend on visiting order); `seeds` where a cell is empty.
template <class VoxelOf>
std::vector<uint32_t> NearestToCentroids(const NodeCoordinates& nodes,
                                         const std::vector<uint32_t>& cell, const CellStats& stats,
                                         const VoxelOf& voxel_of,
                                         const std::vector<uint32_t>& seeds) {
  std::vector<double> best(seeds.size(), std::numeric_limits<double>::max());
  std::vector<uint32_t> moved(seeds);
  nodes.ForEach([&](uint32_t n, int32_t x, int32_t y, int32_t z) {
    const uint32_t c = cell[voxel_of(n)];
    if (c == kNoCell) return;
    const double d2 = Norm2(Vec3(x, y, z) - stats.Centroid(c));
    if (d2 < best[c]) {
      best[c] = d2;
      moved[c] = n;
    }
  });
  return moved;
}

}  // namespace

absl::StatusOr<Scvd> BuildScvd(const VoxelSet& set, const NeighborTable& neighbors,
                               const Components& components, double mean_thickness,
                               const ScvdOptions& options, const Progress& progress) {
  const double t =
      options.mean_thickness_voxels > 0 ? options.mean_thickness_voxels : mean_thickness;
  SM_RETURN_IF_ERROR(Validate(set, t, options));
  Scvd scvd;
  scvd.mean_thickness = t;
  scvd.cell_volume = CellVolume(t, options.radius_voxels);
  const uint32_t num_components = components.count();
  if (options.generator_count > 0 && options.generator_count < num_components) {
    return absl::InvalidArgumentError(
        absl::StrCat("SCVD generator_count ", options.generator_count, " is below the ",
                     num_components, " connected components of the sheet (each needs one)"));
  }

  // The nodes cells grow over: voxels, or columns of voxels.
  const bool columns = options.domain == ScvdDomain::kColumns ||
                       (options.domain == ScvdDomain::kAuto &&
                        options.radius_voxels < options.auto_column_ratio * t);
  scvd.columns = columns;
  ColumnGraph cg;
  if (columns) {
    const uint32_t cap =
        static_cast<uint32_t>(std::max(1.0, std::floor(options.max_column_thickness * t)));
    const auto block = static_cast<uint32_t>(std::clamp(std::round(t), 1.0, 64.0));
    SM_ASSIGN_OR_RETURN(cg, BuildColumnGraph(set, neighbors, cap, block, options.origin));
  }
  const uint32_t num_nodes = columns ? cg.num_nodes() : static_cast<uint32_t>(set.size());
  auto voxel_of = [&](uint32_t n) { return columns ? cg.node_voxel[n] : n; };

  std::vector<uint32_t> seeds;
  if (!options.generators.empty()) {
    seeds = GivenSeeds(set, components, columns ? &cg : nullptr, options, &scvd);
    if (seeds.empty()) {
      return absl::InvalidArgumentError(absl::StrCat(
          "SCVD: none of the ", options.generators.size(), " given generators is on the sheet"));
    }
  } else if (options.local) {
    SM_ASSIGN_OR_RETURN(
        seeds, SeedLocally(set, components, num_nodes, columns ? &cg : nullptr, options, &scvd));
  } else {
    SM_ASSIGN_OR_RETURN(seeds,
                        SeedGenerators(set, components, num_nodes, voxel_of, options, &scvd));
  }

  const NodeCoordinates nodes(set, columns ? &cg : nullptr, options.origin);
  std::vector<Index3> gen(seeds.size());
  for (size_t i = 0; i < seeds.size(); ++i) gen[i] = set.CoordOf(voxel_of(seeds[i]));

  const bool given = !options.generators.empty();
  const int max_growths = given ? 1 : std::max(1, options.lloyd_max_iter + 1);
  std::vector<uint32_t> cell(set.size());
  CellStats stats;
  for (int it = 0; it < max_growths; ++it) {
    const Progress step = progress.Sub(double(it) / max_growths, double(it + 1) / max_growths);
    std::vector<uint32_t> node_cell;
    if (columns) {
      SM_ASSIGN_OR_RETURN(node_cell, GrowCells(cg.graph, seeds, step));
      for (uint32_t v = 0; v < cell.size(); ++v) cell[v] = node_cell[cg.node_of_voxel[v]];
    } else {
      std::vector<uint32_t>().swap(cell);  // not needed while the cells grow again
      SM_ASSIGN_OR_RETURN(cell, GrowCells(neighbors, seeds, step));
    }
    stats = Accumulate(set, options.origin, cell, gen, options.density);
    scvd.energy.push_back(stats.energy);
    scvd.iterations = it + 1;
    if (it > 0 && !options.local && !given) {
      const double prev = scvd.energy[it - 1];
      if (prev <= 0 || std::abs(prev - stats.energy) / prev < options.lloyd_tol) {
        scvd.converged = true;
        break;
      }
    }
    if (it + 1 == max_growths) break;
    // Formula 2 with ρ = 1: the centroid; the generator moves to the node of its cell
    // nearest to it, since the centroid of a curved sheet can fall off the sheet.
    std::vector<uint32_t> moved = NearestToCentroids(nodes, cell, stats, voxel_of, seeds);
    if (moved == seeds) {
      scvd.converged = true;
      break;
    }
    seeds.swap(moved);
    for (size_t i = 0; i < seeds.size(); ++i) gen[i] = set.CoordOf(voxel_of(seeds[i]));
  }
  scvd.generator_voxel.resize(seeds.size());
  for (size_t i = 0; i < seeds.size(); ++i) scvd.generator_voxel[i] = voxel_of(seeds[i]);
  scvd.generators = std::move(gen);
  scvd.cell_size = std::move(stats.count);
  scvd.centroid.resize(scvd.generators.size());
  for (size_t c = 0; c < scvd.centroid.size(); ++c) {
    scvd.centroid[c] = scvd.cell_size[c] > 0 ? stats.Centroid(c) - Vec3::Of(options.origin)
                                             : Vec3::Of(scvd.generators[c]);
  }
  scvd.adjacency = CellAdjacency(neighbors, cell);
  scvd.cell = std::move(cell);
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return scvd;
}

}  // namespace sheetmesh
