// Flips for the improvement of a tetrahedral mesh: edge removal (the optimal triangulation
// of the ring around an edge: 3-2, 4-4, 5-6, ... flips) and 2-3 face removal, never
// removing a face of a facet. Each is kept only if it raises the worst tetrahedron it
// touches (mean < 0) or the mesh's mean without lowering that worst (mean >= 0: the mean
// quality before). Internal to the improvement.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_TET_FLIPS_H_
#define SHEETMESH_WORKER_PIPELINE_TET_TET_FLIPS_H_

#include <cstdint>

#include "worker/pipeline/tet/tet_mesh_editor.h"

namespace sheetmesh {

// Replaces the tetrahedra around the edge (u, v) by the best triangulation of the ring of
// their other vertices, each triangle joined to u and to v (Shewchuk's edge removal).
// False (nothing changed) when no triangulation is better, the edge lies on a facet or the
// boundary, more than 7 tetrahedra share it, or the m tetrahedra around it would become
// 2m - 4, more than m + max_added.
bool RemoveEdge(TetMeshEditor& ed, uint32_t u, uint32_t v, double mean = -1, int max_added = 3);

// The 2-3 flip of the face of tetrahedron t opposite its vertex `f` (one more
// tetrahedron: not when max_added < 1).
bool RemoveFace(TetMeshEditor& ed, uint32_t t, int f, double mean = -1, int max_added = 1);

enum class Flip { kNone, kEdge, kFace };

// One flip around tetrahedron t: the first of its six edges, then of its four faces, that
// flips, adding at most max_added tetrahedra (a budget's room; 3 is any flip). Returns
// which kind flipped.
Flip FlipAround(TetMeshEditor& ed, uint32_t t, double mean, int max_added = 3);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_TET_FLIPS_H_
