// The regions of a volume mesh with bodies: which tetrahedra fill each body (a piece meshed
// as the closed surface around its voxels) and which are rock.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_TET_REGIONS_H_
#define SHEETMESH_WORKER_PIPELINE_TET_TET_REGIONS_H_

#include <cstdint>
#include <vector>

#include "common/types.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/tet/tet_mesh.h"

namespace sheetmesh {

// Per tetrahedron of `mesh`: the body piece (of surface.body_pieces) it lies inside, -1 in
// the rock. The tetrahedra connected across faces that bound no body form a region; each
// region goes to the body that holds the centroids of most of (up to 64 of) its tetrahedra,
// tested against the bodies' closed surfaces in `surface` (voxel index coordinates placed
// by `placement`), or to the rock. Empty when `surface` has no bodies.
std::vector<int32_t> AssignRegions(const TetMesh& mesh, const TriangleMesh& surface,
                                   const Placement& placement);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_TET_REGIONS_H_
