// BuildVolumeMesh: the tetrahedral mesh of the rock block with the sheets as tagged
// internal faces (paper §2.3.1, Figs. 10 and 14): PLC, TetGen, a conformity check that
// every sheet triangle is made of tetrahedron faces, and the quality of Table 3.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESHER_H_
#define SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESHER_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/tet/plc.h"
#include "worker/pipeline/tet/tet_improve.h"
#include "worker/pipeline/tet/tetgen_runner.h"
#include "worker/pipeline/tet/volume_mesh_stats.h"

namespace sheetmesh {

struct VolumeMeshOptions {
  PlcOptions plc;
  TetgenOptions tetgen;
  TetImproveOptions improve;  // the clean-up of TetGen's output
  // A solver's budget: the mesh has at most this many tetrahedra (0: no bound). Where
  // TetGen's mesh of the seeded PLC leaves the improvement too little room (it takes over
  // three quarters of it), the lattice is coarsened, by the prediction (6 tetrahedra per PLC
  // point) and then by TetGen's count, then goes (TetGen's own sizing gives the improvement
  // the best start), and last is 8 median edges; the improvement adds no more than the
  // budget allows. The least possible is TetGen's mesh at that coarsest lattice (or with
  // none, when plc.lattice is 0): a budget below it is kInvalidArgument naming it.
  uint64_t max_tetrahedra = 0;
  // Rounds of refining the sheet triangles around slivers they pin (RefineAtSlivers; 0:
  // none), each a TetGen run and an improvement of its own. Over the 140 runs of the volume
  // mesh sweep a third round was never kept (bench/RESULTS.md, issue 41). Users turn it off
  // with tet.min_dihedral = 0, its aim; tests of the steps before it turn it off here.
  int sliver_rounds = 2;
};

// Meshes the box of `dims` (placed by `placement`) with `sheets` (voxel index coordinates)
// as internal faces; the pieces that are bodies (sheets.body_pieces) bound regions of
// their own (TetMesh::tet_region). Each sheet face carries its aperture (face_aperture_voxels, else
// face_thickness_voxels) as the volume mesh's face_thickness_voxels. kFailedPrecondition when sheet
// triangles intersect (naming them); kInternal when the output does not conform (naming the first
// sheet triangle not covered) or the tetrahedra do not fill the box; TetGen's errors pass through.
absl::StatusOr<VolumeMeshResult> BuildVolumeMesh(const TriangleMesh& sheets, const Dims& dims,
                                                 const Placement& placement,
                                                 const VolumeMeshOptions& options,
                                                 const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESHER_H_
