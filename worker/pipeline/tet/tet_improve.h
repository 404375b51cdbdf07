// Improvement of TetGen's output (ALGORITHM §10–11). TetGen's refinement bounds the
// radius–edge ratio, which does not see slivers (four nearly coplanar vertices, most often
// all on a sheet), and leaves a mean smallest dihedral angle near 40°. This pass raises the
// quality without touching the sheets, in rounds of:
//  - flips that never remove a face on a facet: edge removal (the optimal triangulation of
//    the ring around an edge: 3-2, 4-4, 5-6, ... flips) and 2-3 face removal, first for the
//    worst tetrahedron they touch, then for the mean;
//  - a new vertex off a sliver that the flips cannot mend, inserted into a star-shaped
//    cavity that never crosses a facet; or, for the few slivers whose corners the sheets
//    pin (split_sheets_below_degrees), a new vertex on a sheet face or sheet edge beside
//    it, splitting that face in three or the faces on that edge in two, each piece keeping
//    its input triangle, piece and thickness;
//  - smoothing of the vertices: box vertices slide within their face or edge, so the
//    domain is unchanged; the vertices TetGen added on a sheet slide within the sheet
//    triangle or along the sheet edge they lie on, so the sheets are unchanged too (their
//    faces still tile every input triangle); the PLC's own sheet vertices off the box move
//    at most sheet_move_voxels (half at a junction), and only to raise a star's worst below
//    split_sheets_below_degrees (four sheet vertices nearly on one circle: a sliver no
//    vertex off the sheets can mend). Those few moves are the only change to the sheets.
// A flip or an insertion is kept only if it raises the worst tetrahedron it touches (or,
// for the mean, raises the mean without lowering that worst), and nothing ever inverts.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_TET_IMPROVE_H_
#define SHEETMESH_WORKER_PIPELINE_TET_TET_IMPROVE_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "common/progress.h"
#include "worker/pipeline/tet/tet_improve_options.h"
#include "worker/pipeline/tet/tet_mesh.h"
#include "worker/pipeline/tet/tet_quality.h"

namespace sheetmesh {

// Improves `mesh` in place. Nodes [0, input_nodes) are the PLC's vertices; on a sheet they
// move only as options.sheet_move_voxels allows (the caller takes their new places back). The faces
// (the facets' triangles, box and sheets) stay faces, each of them within the facet it tiles, and
// vertices on the box faces stay on them, so the mesh keeps conforming to the PLC bounded by
// [box_lo, box_hi]. Tetrahedra must be positively oriented (TetVolume > 0). Returns kCancelled if
// `progress` asks, leaving a valid mesh.
absl::Status ImproveTetMesh(TetMesh* mesh, const Vec3& box_lo, const Vec3& box_hi,
                            uint32_t input_nodes, const TetImproveOptions& options,
                            TetImproveReport* report, const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_TET_IMPROVE_H_
