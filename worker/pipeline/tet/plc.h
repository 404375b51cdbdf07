// The piecewise-linear complex (PLC) handed to TetGen (paper §2.3.1, Fig. 10; ALGORITHM
// §10): the domain box plus the sheet triangles as internal facets, in physical units.
// Sheets that reach the box end on it: their vertices within a snapping distance of a box
// face move onto it, and their edges and points there are embedded in that face's facet.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_PLC_H_
#define SHEETMESH_WORKER_PIPELINE_TET_PLC_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "common/types.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/tet/plc_types.h"

namespace sheetmesh {

// The narrowest angle at which facets meet in an edge (sheet and sheet, a sheet folded
// on itself, sheet and box face), degrees: the tetrahedra in that wedge can have no
// larger dihedral angle there, in any mesh that keeps the facets.
struct WedgeBound {
  double narrowest_degrees = 360;  // 360: no facets meet in an edge
  uint32_t narrow_edges = 0;       // edges with a wedge under the aim asked for
};
WedgeBound MeasureWedges(const Plc& plc, double below_degrees);

// Builds the PLC of `sheets` (voxel index coordinates; face_piece and face_thickness_voxels used
// when present) in the box of `dims` placed by `placement`. kFailedPrecondition listing
// the first clashing triangles (ids and coordinates) when sheet facets intersect and
// options.repair is off; kInvalidArgument for empty dims.
absl::StatusOr<Plc> BuildPlc(const TriangleMesh& sheets, const Dims& dims,
                             const Placement& placement, const PlcOptions& options = {},
                             std::vector<Clash>* clashes = nullptr);

// Refines each marked sheet triangle (of plc->sheet_triangles) by longest-edge bisection
// until its longest edge is half what it was: an edge is split at its middle (a new vertex
// appended) once it is the longest of every sheet triangle on it, the others refined along
// their own longest edge first, so no angle falls below half of what it was and the
// sheets keep their shape. Edges in a box face are not split (a triangle whose chain reaches
// one stays as it is). The new triangles are appended, each with its facet, piece and
// thickness. Returns the number of edges split.
uint32_t RefineSheetTriangles(const std::vector<uint8_t>& marked, Plc* plc);

// Removes the marked sheet triangles (of plc->sheet_triangles) with their facets; the
// others keep their order and are numbered again (marker kFirstSheetMarker + index). Their
// vertices stay (points of the PLC). Returns the number removed.
uint32_t DropSheetTriangles(const std::vector<uint8_t>& drop, Plc* plc);

// Moves the lattice seeds (the last plc->seed_points vertices, on no facet) by a fixed
// pseudo-random offset of at most voxels / 2 per coordinate, drawn for `salt`: TetGen 1.5
// crashes on some PLCs (a segfault while recovering facets with -Y) and meshes the same
// sheets with the seeds a thousandth of a voxel elsewhere; where the seeds go is free.
void MoveSeeds(uint32_t salt, double voxels, Plc* plc);
// Moves each sheet vertex by a fixed pseudo-random offset of at most voxels / 2 per
// coordinate, drawn for `salt`, but not off a box face it lies on: TetGen 1.5 crashes on some
// PLCs whatever the seeds (DPM at r = 3: a segfault recovering segments with -Y) and meshes
// them with the sheet vertices a millionth of a voxel elsewhere (a degenerate configuration
// of the sheets' own vertices, gone at that size).
void JitterSheetVertices(uint32_t salt, double voxels, Plc* plc);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_PLC_H_
