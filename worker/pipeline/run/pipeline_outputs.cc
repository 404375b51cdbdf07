#include "worker/pipeline/run/pipeline_outputs.h"

#include <filesystem>

#include "common/status_macros.h"
#include "worker/pipeline/mesh/mesh_io.h"
#include "worker/pipeline/tet/volume_mesh_io.h"

namespace sheetmesh {
namespace {

std::string In(const std::string& dir, const char* name) {
  return (std::filesystem::path(dir) / name).string();
}

}  // namespace

absl::Status WriteSurfaceFiles(const std::string& dir, const TriangleMesh& mesh,
                               const Placement& placement, const OutputOptions& output,
                               std::vector<std::string>* files) {
  if (output.ply) {
    SM_RETURN_IF_ERROR(WritePly(In(dir, "surface.ply"), mesh, placement));
    files->push_back("surface.ply");
  }
  if (output.vtp) {
    SM_RETURN_IF_ERROR(WriteVtp(In(dir, "surface.vtp"), mesh, placement));
    files->push_back("surface.vtp");
  }
  if (output.surface_vtu) {
    SM_RETURN_IF_ERROR(WriteSurfaceVtu(In(dir, "surface.vtu"), mesh, placement));
    files->push_back("surface.vtu");
  }
  if (output.obj) {
    SM_RETURN_IF_ERROR(WriteObj(In(dir, "surface.obj"), mesh, placement));
    files->push_back("surface.obj");
  }
  return absl::OkStatus();
}

absl::Status WriteVolumeFiles(const std::string& dir, const TetMesh& mesh,
                              const OutputOptions& output, std::vector<std::string>* files,
                              const VolumeFields* fields, SplitStats* split) {
  if (output.vtu) {
    SM_RETURN_IF_ERROR(WriteVtu(In(dir, "volume.vtu"), mesh, fields));
    files->push_back("volume.vtu");
  }
  if (output.msh) {
    SM_RETURN_IF_ERROR(WriteGmsh(In(dir, "volume.msh"), mesh));
    files->push_back("volume.msh");
  }
  if (output.inp) {
    SM_RETURN_IF_ERROR(WriteAbaqus(In(dir, "volume.inp"), mesh));
    files->push_back("volume.inp");
  }
  if (output.exo) {
    SM_RETURN_IF_ERROR(WriteExodus(In(dir, "volume.exo"), mesh));
    files->push_back("volume.exo");
  }
  if (!output.split) return absl::OkStatus();
  SM_ASSIGN_OR_RETURN(const SplitMesh s, SplitAlongSheets(mesh));
  if (split != nullptr) *split = s.stats;
  if (output.inp) {
    SM_RETURN_IF_ERROR(WriteSplitAbaqus(In(dir, "volume_split.inp"), s, false));
    SM_RETURN_IF_ERROR(WriteSplitAbaqus(In(dir, "volume_split_ccx.inp"), s, true));
    files->push_back("volume_split.inp");
    files->push_back("volume_split_ccx.inp");
  }
  if (output.exo) {
    SM_RETURN_IF_ERROR(WriteSplitExodus(In(dir, "volume_split.exo"), s));
    files->push_back("volume_split.exo");
  }
  return absl::OkStatus();
}

}  // namespace sheetmesh
