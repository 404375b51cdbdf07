// What the volume mesher checks and says of TetGen's and the improvement's mesh: that it
// conforms to the PLC, sheet faces TetGen listed wrongly taken again, the sheet vertices'
// moves the angles do not need taken back, and the warning for a minimum under the aim.
// Internal to the volume mesher (volume_mesher.cc).
#ifndef SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESH_CHECKS_H_
#define SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESH_CHECKS_H_

#include <cstdint>

#include "worker/pipeline/tet/volume_mesh_stats.h"

namespace sheetmesh {

// Whether the mesh's nodes of the PLC's sheet vertices have the PLC's numbers, each within
// `slack` of its place in the PLC (TetGen drops a point that coincides with another and
// numbers the rest again: then they may not).
bool NodesFollowPlc(const Plc& plc, const TetMesh& mesh, double slack);

// Whether every sheet triangle of `plc` is exactly tiled by faces of the mesh's tetrahedra.
Conformity CheckConformity(const Plc& plc, const TetMesh& mesh);

// TetGen 1.5 at times lists triangles for a sheet facet that are not faces of its
// tetrahedra (seen on the NETL fracture, all on one sheet triangle) while the tetrahedra
// do cover the facet. Then the sheet faces are taken again from the tetrahedra. Returns how
// many sheet facets had faces that are no tetrahedron's (0: the list is kept as TetGen wrote
// it); the conformity check then verifies the result.
uint32_t RederiveFacetFaces(const Plc& plc, TetMesh* mesh);

// The PLC's sheet vertices the improvement moved go back towards their place in the PLC
// (in quarters) as far as each one's star stays at or above `keep_above`; a vertex on a
// sheet triangle the improvement split stays (the pieces lie in the plane it made).
// Recounts the moved vertices and the farthest move in r->improvement. Returns how many
// went all the way back.
uint32_t TakeBackSheetMoves(const Plc& plc, double keep_above, VolumeMeshResult* r);

// Sets report->moved_sheet_vertices and max_sheet_move: the sheet vertices of `from` that
// `mesh` has elsewhere (REQUIRES: the mesh's nodes number them as `from` does, as
// NodesFollowPlc checks).
void CountSheetMoves(const Plc& from, const TetMesh& mesh, TetImproveReport* report);

// Puts the PLC's sheet vertices where the mesh has them (the improvement may have moved
// them; REQUIRES as for CountSheetMoves).
void SheetVerticesFromMesh(const TetMesh& mesh, Plc* plc);

// The warning for a minimum `worst` under the aim: where the worst tetrahedron is (in the
// units of `placement`; the caller places it), how many of its corners the sheets hold,
// and why (`wedge`: the input's narrowest wedge).
AngleWarning DescribeWorst(const TetMesh& mesh, double worst, double aim, double wedge,
                           const Placement& placement);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESH_CHECKS_H_
