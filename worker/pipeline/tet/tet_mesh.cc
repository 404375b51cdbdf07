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

TriangleMesh TetMesh::SheetSurface(const Placement& placement) const {
  TriangleMesh out;
  out.body_pieces = body_pieces;
  std::vector<uint32_t> index(nodes.size(), UINT32_MAX);
  for (size_t f = 0; f < faces.size(); ++f) {
    if (face_piece[f] < 0) continue;
    Face g;
    for (int k = 0; k < 3; ++k) {
      uint32_t& i = index[faces[f][k]];
      if (i == UINT32_MAX) {
        i = static_cast<uint32_t>(out.vertices.size());
        const Vec3& p = nodes[faces[f][k]];
        out.vertices.push_back({(p.x - placement.origin.x) / placement.spacing.x,
                                (p.y - placement.origin.y) / placement.spacing.y,
                                (p.z - placement.origin.z) / placement.spacing.z});
      }
      g[k] = i;
    }
    out.faces.push_back(g);
    out.face_piece.push_back(face_piece[f]);
    out.face_thickness_voxels.push_back(face_thickness_voxels[f]);
  }
  return out;
}

}  // namespace sheetmesh
