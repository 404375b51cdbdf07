// Edge contraction for the improvement of a tetrahedral mesh: a sliver with a corner inside
// the rock (on no facet, free to go) or one the sheets can do without, whose neighbourhood
// is better without that corner, merged into another vertex. Flips cannot remove a vertex and
// smoothing cannot take it out of a gap it is trapped in (an inserted point pressed between two
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

// Merges a sheet vertex u of t's that TetGen or the improvement added (sliding in its sheet
// triangle or along its sheet edge) into a neighbour w along the sheets, where the sheets
// keep their shape exactly: w lies in the plane of every sheet face at u it enters (a
// corner of u's fan in its triangle; the next vertex along u's edge), each such face keeps
// its side. The sheet faces holding (u, w) go, the rest take w for u; the tetrahedra as
// ContractEdgeOf. The improvement's own splits leave clusters of such vertices a tenth of
// a voxel apart whose slivers no move or insertion mends. Returns whether it contracted.
bool ContractSheetEdgeOf(TetMeshEditor& ed, const VertexFreedom& freedom, uint32_t t);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_TET_CONTRACTION_H_
