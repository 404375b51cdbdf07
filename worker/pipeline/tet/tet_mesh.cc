#include "worker/pipeline/tet/tet_mesh.h"

#include "absl/strings/str_format.h"
#include "worker/pipeline/tet/plc.h"

namespace sheetmesh {

size_t TetMesh::num_sheet_faces() const {
  size_t n = 0;
  for (int32_t m : face_marker) n += m >= kFirstSheetMarker;
  return n;
}

std::string TetMesh::UnitsText() const {
  if (unit.empty()) {
    return voxel_length == 1.0
               ? std::string("lengths in voxels")
               : absl::StrFormat("lengths in the volume's unit (not given; a voxel is %.9g)",
                                 voxel_length);
  }
  return absl::StrFormat("lengths in %s (a voxel is %.9g %s)", unit, voxel_length, unit);
}

}  // namespace sheetmesh
