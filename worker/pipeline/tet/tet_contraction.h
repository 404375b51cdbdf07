// Edge contraction for the improvement of a tetrahedral mesh: a sliver with a corner inside
// the rock (on no facet, free to go) whose neighbourhood is better without that corner,
// merged into one of the sliver's other corners. Flips cannot remove a vertex and smoothing
// cannot take it out of a gap it is trapped in (an inserted point pressed between two
// sheets, a lattice seed beside a sheet vertex); contraction can. Internal to the
// improvement.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_TET_CONTRACTION_H_
#define SHEETMESH_WORKER_PIPELINE_TET_TET_CONTRACTION_H_

#include <cstdint>

#include "worker/pipeline/tet/tet_mesh_editor.h"
#include "worker/pipeline/tet/vertex_freedom.h"

namespace sheetmesh {

// Merges a free corner u of tetrahedron t into another corner w of t: the tetrahedra
// holding the edge (u, w) go, the rest of u's star take w for u. Of the ways t allows, the
// one whose new tetrahedra have the best worst is taken, if that worst is above the worst
// of u's star as it was, every new tetrahedron is positively oriented and they fill what
// u's star filled. No facet face is removed (u lies on none). Returns whether it contracted
// (u is then in no tetrahedron; TetMesh's nodes keep it until RemoveUnusedNodes).
bool ContractEdgeOf(TetMeshEditor& ed, const VertexFreedom& freedom, uint32_t t);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_TET_CONTRACTION_H_
