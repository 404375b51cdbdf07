#include "worker/pipeline/tet/tet_mesh.h"

#include <algorithm>
#include <array>

#include "absl/container/flat_hash_set.h"
#include "absl/strings/str_format.h"
#include "worker/pipeline/tet/plc.h"

namespace sheetmesh {

uint32_t TetMesh::RemoveUnusedNodes() {
  std::vector<uint32_t> id(nodes.size(), UINT32_MAX);
  for (const Tet& t : tets) {
    for (uint32_t v : t) id[v] = 0;
  }
  for (const auto& f : faces) {
    for (uint32_t v : f) id[v] = 0;
  }
  uint32_t kept = 0;
  for (size_t v = 0; v < nodes.size(); ++v) {
    if (id[v] == UINT32_MAX) continue;
    id[v] = kept;
    nodes[kept++] = nodes[v];
  }
  const uint32_t removed = static_cast<uint32_t>(nodes.size()) - kept;
  if (removed == 0) return 0;
  nodes.resize(kept);
  for (Tet& t : tets) {
    for (uint32_t& v : t) v = id[v];
  }
  for (auto& f : faces) {
    for (uint32_t& v : f) v = id[v];
  }
  return removed;
}

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
  auto add = [&](const std::array<uint32_t, 3>& face, int32_t piece, float thickness) {
    Face g;
    for (int k = 0; k < 3; ++k) {
      uint32_t& i = index[face[k]];
      if (i == UINT32_MAX) {
        i = static_cast<uint32_t>(out.vertices.size());
        const Vec3& p = nodes[face[k]];
        out.vertices.push_back({(p.x - placement.origin.x) / placement.spacing.x,
                                (p.y - placement.origin.y) / placement.spacing.y,
                                (p.z - placement.origin.z) / placement.spacing.z});
      }
      g[k] = i;
    }
    out.faces.push_back(g);
    out.face_piece.push_back(piece);
    out.face_thickness_voxels.push_back(thickness);
  };
  for (size_t f = 0; f < faces.size(); ++f) {
    if (face_piece[f] >= 0) add(faces[f], face_piece[f], face_thickness_voxels[f]);
  }
  if (tet_region.empty()) return out;
  // A body cut by the box is bounded there by box faces, which are no sheet's: its walls
  // alone are open, and filling them by the parity of crossings fills the wrong side. Its
  // region's tetrahedra's faces on the box close it (with no thickness: they add no prism).
  absl::flat_hash_set<std::array<uint32_t, 3>> on_box;
  for (size_t f = 0; f < faces.size(); ++f) {
    if (face_piece[f] >= 0) continue;
    std::array<uint32_t, 3> key = faces[f];
    std::sort(key.begin(), key.end());
    on_box.insert(key);
  }
  for (size_t t = 0; t < tets.size(); ++t) {
    if (tet_region[t] < 0) continue;
    for (int k = 0; k < 4; ++k) {
      const std::array<uint32_t, 3> face = {tets[t][(k + 1) % 4], tets[t][(k + 2) % 4],
                                            tets[t][(k + 3) % 4]};
      std::array<uint32_t, 3> key = face;
      std::sort(key.begin(), key.end());
      if (on_box.contains(key)) add(face, tet_region[t], 0);
    }
  }
  return out;
}

}  // namespace sheetmesh
