// A piece meshed as a body: the closed surface around its voxels (not a mid-surface with
// a thickness), for pieces as thick as they are wide — a vug, a dissolution slab — where one
// layer of prisms cannot follow both walls. The volume mesh tetrahedralizes its inside as
// a region of its own.
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_BODY_SURFACE_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_BODY_SURFACE_H_

#include <cstdint>
#include <map>
#include <optional>

#include "absl/status/statusor.h"
#include "worker/pipeline/mesh/decimate.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

struct BodySurface {
  TriangleMesh mesh;                        // face_piece = the piece, face_thickness_voxels 0
  uint64_t faces_before = 0;                // at voxel resolution, before decimation
  std::optional<DecimateStats> decimation;  // when triangles asked for fewer
};

// The boundary of `voxels` at voxel resolution (a dual surface between the voxels' centres
// and their outside neighbours'), oriented outward, within the box of the set's dims
// ([-0.5, n - 0.5] on each axis: a piece reaching the box is closed by faces lying in the
// box's face), then decimated to `triangles` when that is > 0 and fewer
// than it has. Faces carry `piece` and thickness 0. kInvalidArgument for an empty set.
absl::StatusOr<BodySurface> MeshBody(const VoxelSet& voxels, int32_t piece, uint64_t triangles);

// Each body's equivalent aperture 2 V / A, in voxels, by piece (the pieces `mesh.body_pieces`
// lists that have faces): V the volume its closed surface encloses (the divergence theorem;
// its size, whichever way the faces turn), A the area of its walls, the faces lying in a
// face of the box of `dims` left out, as the volume mesh and the flow leave them out (a slab
// across the box has the aperture of the gap between its two walls). A body with no wall
// area is left out.
std::map<int32_t, double> EquivalentApertures(const TriangleMesh& mesh, const Dims& dims);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_BODY_SURFACE_H_
