// SCVD: the simplified centroidal Voronoi diagram of a sheet (paper §2.1, Algorithm 1,
// formulas 2 and 3; ALGORITHM §2-3). Cells grow from generators by synchronous
// breadth-first search over face neighbours; Lloyd steps move each generator to the voxel
// of its cell nearest the cell's centroid until the energy settles.
#ifndef SHEETMESH_WORKER_PIPELINE_SCVD_SCVD_H_
#define SHEETMESH_WORKER_PIPELINE_SCVD_SCVD_H_

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "common/types.h"
#include "worker/pipeline/voxel/components.h"
#include "worker/pipeline/voxel/neighbor_table.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// What the cells grow over.
enum class ScvdDomain {
  kVoxels,   // sheet voxels, face neighbours (Algorithm 1 as the paper states it)
  kColumns,  // columns across the thickness (see column_graph.h): no stacking when r is close
             // to the thickness (beyond the paper)
  kAuto,     // columns when r < auto_column_ratio * t̄, voxels otherwise: measured on the
             // test volumes, columns win where cells would stack and voxels follow curved
             // sheets better once cells are wider than the sheet (bench/RESULTS.md)
};

struct ScvdOptions {
  double radius_voxels = 7.0;          // r of formula 3: the cell radius, the size parameter
  double mean_thickness_voxels = 0.0;  // t̄ of formula 3; 0 = the caller's measured mean
  int64_t generator_count = 0;         // > 0: this many generators in all (spread over the
                                       // components by size) instead of formula 3
  uint64_t seed = 1;                   // seeds the random choice of the first generators
  int lloyd_max_iter = 20;             // Lloyd steps at most
  double lloyd_tol = 1e-3;             // stop when the energy changes by less (relative)
  ScvdDomain domain = ScvdDomain::kAuto;
  double auto_column_ratio = 1.2;     // kAuto: the r / t̄ below which columns are used
  double max_column_thickness = 3.0;  // kColumns: runs longer than this many t̄ are extent,
                                      // not thickness, and are not merged into columns
  // Local: every choice depends only on the sheet near it, so a brick of the volume with a
  // halo builds the cells of its core as the whole volume does (issue 47). Generators are
  // drawn by hashes of global positions (origin + coordinates) on a grid fixed in the
  // volume (local_seeds.h: formula 3 in expectation, or generator_count / the set's voxels
  // per voxel), their ids follow the nodes' (z, y, x) order so ties go the same way in any box
  // that holds them, centroids are taken in global coordinates, and exactly lloyd_max_iter
  // Lloyd steps run (lloyd_tol is not used: the energy is the whole diagram's); a fixed
  // point still ends them. Not with a density (its normalisation is global).
  bool local = false;
  // With local: generators spaced like blue noise (LocalDraw::spacing), not drawn one by
  // one; measured in bench/RESULTS.md ("the local draw spaced").
  bool local_spacing = true;
  Index3 origin;  // the global position of the set's voxel (0, 0, 0); non-negative
  // Given: these generators (global positions; those off the set's nodes are passed by,
  // two on one node count once) and one growth, no Lloyd step — a brick's second pass,
  // after the generators of all bricks are gathered. Implies local's ids and coordinates.
  // The caller keeps it alive.
  std::span<const Index3> generators;
  // ρ of formula 2, one per voxel of the set, all positive; empty: ρ = 1. Centroids and the
  // energy weigh each voxel by it, and seeds are drawn as sqrt ρ, so cells are smaller
  // where it is larger. The caller keeps it alive.
  std::span<const float> density;
};

// V_vol of formula 3: t̄ (1 + 2 r (r - 1)), the voxels of one cell.
double CellVolume(double mean_thickness, double radius);
// Generators of a component of `voxels` voxels: max(1, round(voxels / V_vol)).
int64_t GeneratorsForComponent(uint64_t voxels, double cell_volume);

inline constexpr uint32_t kNoCell = UINT32_MAX;

// The diagram. Generator ids are dense, 0..num_generators()-1, ordered by component then
// by the order of choice.
struct Scvd {
  std::vector<uint32_t> generator_voxel;      // voxel index (in the set) of each generator
  std::vector<Index3> generators;             // and its coordinates
  std::vector<uint32_t> generator_component;  // component of each generator
  std::vector<uint32_t> cell;                 // generator of each voxel
  std::vector<uint32_t> cell_size;            // voxels per cell
  std::vector<Vec3> centroid;                 // centroid of each cell (formula 2)
  std::vector<std::pair<uint32_t, uint32_t>> adjacency;  // cells whose fronts met, a < b
  std::vector<double> energy;                            // E after each growth
  int iterations = 0;                                    // growths done
  bool converged = false;                                // stopped by lloyd_tol or a fixed point
  double cell_volume = 0;                                // V_vol used
  double mean_thickness = 0;                             // t̄ used
  bool columns = false;                                  // grown over columns (not voxels)

  uint32_t num_generators() const { return static_cast<uint32_t>(generators.size()); }
};

struct CsrGraph;  // column_graph.h

// Grows cells from `seeds` (node ids, one per cell, distinct) over the edges of `graph`;
// the same rules as the voxel version below.
absl::StatusOr<std::vector<uint32_t>> GrowCells(const CsrGraph& graph,
                                                std::span<const uint32_t> seeds,
                                                const Progress& progress = {});

// Grows cells from `seeds` (voxel indices, one per cell, distinct) over the face
// neighbours of the set: every cell advances one layer per round; a voxel joins the first
// cell to reach it, the lowest id among cells reaching it in the same round. Voxels no
// seed reaches keep kNoCell. Returns the cell of each voxel; kCancelled if asked.
absl::StatusOr<std::vector<uint32_t>> GrowCells(const NeighborTable& neighbors,
                                                std::span<const uint32_t> seeds,
                                                const Progress& progress = {});

// Builds the SCVD of `set`. `components` are its 6-connected components (growth cannot
// cross them, so each gets its own generators); `mean_thickness` is t̄ (used unless
// options.mean_thickness_voxels > 0). kInvalidArgument for r <= 0, a non-positive
// thickness, an empty set, or a generator count below the number of components;
// kCancelled if asked. Deterministic for equal inputs and seed.
absl::StatusOr<Scvd> BuildScvd(const VoxelSet& set, const NeighborTable& neighbors,
                               const Components& components, double mean_thickness,
                               const ScvdOptions& options, const Progress& progress = {});

// The pairs of distinct cells that touch across a face, sorted, a < b.
std::vector<std::pair<uint32_t, uint32_t>> CellAdjacency(const NeighborTable& neighbors,
                                                         std::span<const uint32_t> cell);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SCVD_SCVD_H_
