// The mesh files of a run: the surface (PLY, VTP, OBJ) and the volume mesh (VTU, Gmsh,
// Abaqus) as OutputOptions asks, each written atomically, for `run`, `surface`, `volume`
// and the service alike.
#ifndef SHEETMESH_WORKER_PIPELINE_RUN_PIPELINE_OUTPUTS_H_
#define SHEETMESH_WORKER_PIPELINE_RUN_PIPELINE_OUTPUTS_H_

#include <string>
#include <vector>

#include "absl/status/status.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/run/pipeline_options.h"
#include "worker/pipeline/tet/split_mesh.h"
#include "worker/pipeline/tet/tet_mesh.h"

namespace sheetmesh {

// surface.ply, surface.vtp, surface.obj into `dir` (which must exist), placed by
// `placement`; appends the names written to `files`. Writer errors pass through.
absl::Status WriteSurfaceFiles(const std::string& dir, const TriangleMesh& mesh,
                               const Placement& placement, const OutputOptions& output,
                               std::vector<std::string>* files);

// volume.vtu (with `fields` when given), volume.msh, volume.inp, volume.exo into `dir` (which
// must exist), and with output.split the mesh split along its sheets (volume_split.inp,
// volume_split_ccx.inp, volume_split.exo; what the split did into `split` when given);
// appends their names.
absl::Status WriteVolumeFiles(const std::string& dir, const TetMesh& mesh,
                              const OutputOptions& output, std::vector<std::string>* files,
                              const VolumeFields* fields = nullptr, SplitStats* split = nullptr);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_RUN_PIPELINE_OUTPUTS_H_
