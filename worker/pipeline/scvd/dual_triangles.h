// Triangles from an SCVD (paper §2.3.1, Figs. 8-9; ALGORITHM §4): every 2x2x2 block of
// voxels whose sheet voxels belong to three cells gives the triangle of their generators;
// blocks with four or more cells are resolved by the amending strategy — the cells form a
// polygon along the adjacency recorded while growing, triangulated by its shorter
// diagonals. Candidates are then kept greedily, most-voted first, unless they fold onto or
// cut through a triangle already kept, so the mesh has no duplicate, degenerate or
// self-intersecting faces, and non-manifold edges only where sheets cross.
#ifndef SHEETMESH_WORKER_PIPELINE_SCVD_DUAL_TRIANGLES_H_
#define SHEETMESH_WORKER_PIPELINE_SCVD_DUAL_TRIANGLES_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/scvd/dual_triangle_types.h"
#include "worker/pipeline/scvd/scvd.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// Triangulates `scvd` of `set`; `positions` are the vertex positions of the generators
// (their voxels, or cell centroids); `thickness` is τ per voxel (for rim vertices).
// kCancelled if asked.
absl::StatusOr<DualTriangulation> TriangulateScvd(const VoxelSet& set,
                                                  const NeighborTable& neighbors,
                                                  std::span<const uint16_t> thickness,
                                                  const Scvd& scvd, std::span<const Vec3> positions,
                                                  const DualTriangleOptions& options = {},
                                                  const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SCVD_DUAL_TRIANGLES_H_
