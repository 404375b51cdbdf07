// Separation (paper §2.2.1, Algorithm 2; ALGORITHM §5): cut crossing structures apart.
// A generator is flat when every pair of its triangles that share an edge meets at a
// dihedral angle of at least D_ang and none of its edges has three or more triangles;
// pieces are floods over flat generators through mesh edges; voxels of non-flat cells go.
// Beyond the paper, a fold is also judged at a scale above the roughness: a generator
// whose triangles fold but whose neighbourhood of `fit_rings` mesh edges lies in one plane
// (a rough or thick sheet, not a crossing) stays flat.
#ifndef SHEETMESH_WORKER_PIPELINE_EXTRACT_SEPARATION_H_
#define SHEETMESH_WORKER_PIPELINE_EXTRACT_SEPARATION_H_

#include <cstdint>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/extract/cell_planes.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/voxel/labelled_voxels.h"

namespace sheetmesh {

struct SeparationOptions {
  double radius_voxels = 5.0;        // r of the SCVD built for separation (Fig. 4: r = 5);
                                     // ExtractFeatures takes 0 as max(5, t̄ / 2)
  double dihedral_degrees = 150.0;   // D_ang: below this, two triangles are not flat
  uint64_t seed = 1;                 // SCVD seed
  int widen_rings = 1;               // beyond the paper: a piece that is not planar and
                                     // touches non-flat generators leaked through a missed
                                     // cell; it is flooded again with the non-flat set widened
                                     // by this many mesh edges, and the ring then rejoins the
                                     // piece of most of its neighbours (0: the paper)
  double planarity_threshold = 0.9;  // pieces below this planarity count as leaked
  int fit_rings = 2;                 // beyond the paper: a fold between two triangles cuts only
                                     // when the generators within this many mesh edges do not
                                     // lie in one plane to within the fold D_ang allows
                                     // (0: the paper, every fold cuts)
};

// Flat flags per vertex of `faces` over `positions` (Algorithm 2's test). Vertices with no
// face are flat. With `fit_rings` > 0, a vertex at a fold (not at an edge of three or more
// triangles) stays flat when the vertices within that many edges of it fit one plane:
// sqrt(λ_min / λ_mid) of their covariance at most tan((180° - D_ang) / 2), what two
// half-planes folded at D_ang would give.
std::vector<uint8_t> FlatVertices(std::span<const Vec3> positions, std::span<const Face> faces,
                                  double dihedral_degrees, int fit_rings = 0);

struct SeparationResult {
  LabelledVoxels pieces;        // one label per flood, largest first
  CellPlanes cells;             // the SCVD's cells, cell_of_voxel per voxel of pieces
  uint64_t removed_voxels = 0;  // voxels of non-flat cells
  uint32_t generators = 0;
  uint32_t nonflat_generators = 0;
};

struct ScvdOfSet;  // scvd_of_set.h

// Algorithm 2 over an SCVD already built, restricted to the cells flagged in `cell_in_set`
// (per generator; empty: all): the others are neither flooded nor kept, and their
// triangles do not count. The set must be made of whole cells (its components are).
absl::StatusOr<SeparationResult> SeparateOver(const ScvdOfSet& scvd,
                                              std::span<const uint8_t> cell_in_set,
                                              const SeparationOptions& options,
                                              const Progress& progress = {});

// Separates `set`. kInvalidArgument for r <= 0 or D_ang outside (0, 180]; errors of the
// SCVD pass through; kCancelled if asked.
absl::StatusOr<SeparationResult> Separate(const VoxelSet& set, const SeparationOptions& options,
                                          const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_EXTRACT_SEPARATION_H_
