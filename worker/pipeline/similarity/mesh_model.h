// Mesh models: the voxels a mesh stands for, so it can be compared with the image.
// A sheet mesh stands for its prisms (paper §2.3.2: each triangle is the mid-plane of a
// prism as high as its thickness); a closed surface stands for the volume it encloses.
#ifndef SHEETMESH_WORKER_PIPELINE_SIMILARITY_MESH_MODEL_H_
#define SHEETMESH_WORKER_PIPELINE_SIMILARITY_MESH_MODEL_H_

#include <cstdint>
#include <span>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

enum class PrismHeight {
  kFace,    // one thickness per triangle (mesh.face_thickness_voxels): the paper's prisms
  kVertex,  // thickness interpolated from mesh.vertex_thickness_voxels: a linearly varying shell
};

// Voxels of `dims` whose centre projects into some triangle and lies within half its
// thickness of the triangle's plane (ALGORITHM §9). Triangles of zero thickness add
// nothing. kInvalidArgument when the needed thickness array does not match the mesh.
absl::StatusOr<VoxelSet> VoxelizePrisms(const TriangleMesh& mesh, const Dims& dims,
                                        PrismHeight height = PrismHeight::kFace,
                                        const Progress& progress = {});

// Voxels of `dims` whose centre lies inside the closed surface `mesh` (even-odd rule along
// x). Meant for watertight surfaces such as marching-cubes output; for an open surface the
// result is whatever the parity gives.
absl::StatusOr<VoxelSet> VoxelizeClosedSurface(const TriangleMesh& mesh, const Dims& dims,
                                               const Progress& progress = {});

// The voxels `mesh` stands for: the prisms of its sheets' faces (`height`) and the inside
// of each body (mesh.body_pieces), each body on its own so that two touching bodies do not
// cancel where their faces coincide.
absl::StatusOr<VoxelSet> VoxelizeMesh(const TriangleMesh& mesh, const Dims& dims,
                                      PrismHeight height = PrismHeight::kFace,
                                      const Progress& progress = {});

// Builds a VoxelSet from linear indices (x + nx (y + ny z)), sorted and unique.
VoxelSet VoxelSetFromSortedLinear(const Dims& dims, std::span<const uint64_t> keys);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SIMILARITY_MESH_MODEL_H_
