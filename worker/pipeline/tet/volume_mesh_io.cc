#include "worker/pipeline/tet/volume_mesh_io.h"

#include <algorithm>
#include <map>
#include <set>

#include "absl/container/flat_hash_map.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/file_util.h"
#include "common/version.h"

namespace sheetmesh {
namespace {

// Faces grouped: -1 = boundary, p >= 0 = sheet piece p.
std::map<int32_t, std::vector<size_t>> FaceGroups(const TetMesh& m) {
  std::map<int32_t, std::vector<size_t>> groups;
  for (size_t f = 0; f < m.faces.size(); ++f) groups[m.face_piece[f]].push_back(f);
  return groups;
}

}  // namespace

absl::Status WriteVtu(const std::string& path, const TetMesh& m) {
  const size_t cells = m.tets.size() + m.faces.size();
  std::string out = absl::StrCat(
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
      "byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\"",
      m.nodes.size(), "\" NumberOfCells=\"", cells,
      "\">\n<Points>\n"
      "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n");
  for (const Vec3& p : m.nodes) absl::StrAppendFormat(&out, "%.12g %.12g %.12g\n", p.x, p.y, p.z);
  out +=
      "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" "
      "format=\"ascii\">\n";
  for (const Tet& t : m.tets) absl::StrAppend(&out, t[0], " ", t[1], " ", t[2], " ", t[3], "\n");
  for (const auto& f : m.faces) absl::StrAppend(&out, f[0], " ", f[1], " ", f[2], "\n");
  out += "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  uint64_t off = 0;
  for (size_t i = 0; i < m.tets.size(); ++i) absl::StrAppend(&out, off += 4, "\n");
  for (size_t i = 0; i < m.faces.size(); ++i) absl::StrAppend(&out, off += 3, "\n");
  out += "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (size_t i = 0; i < m.tets.size(); ++i) out += "10\n";
  for (size_t i = 0; i < m.faces.size(); ++i) out += "5\n";
  out +=
      "</DataArray>\n</Cells>\n<CellData Scalars=\"kind\">\n"
      "<DataArray type=\"Int32\" Name=\"kind\" format=\"ascii\">\n";
  for (size_t i = 0; i < m.tets.size(); ++i) out += "0\n";
  for (size_t f = 0; f < m.faces.size(); ++f) out += m.face_piece[f] >= 0 ? "1\n" : "2\n";
  out += "</DataArray>\n<DataArray type=\"Int32\" Name=\"piece\" format=\"ascii\">\n";
  for (size_t i = 0; i < m.tets.size(); ++i) out += "-1\n";
  for (int32_t p : m.face_piece) absl::StrAppend(&out, p, "\n");
  out += "</DataArray>\n<DataArray type=\"Float32\" Name=\"thickness\" format=\"ascii\">\n";
  for (size_t i = 0; i < m.tets.size(); ++i) out += "0\n";
  for (float t : m.face_thickness) absl::StrAppendFormat(&out, "%.7g\n", t);
  out += "</DataArray>\n</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
  return WriteFileAtomically(path, out);
}

absl::Status WriteGmsh(const std::string& path, const TetMesh& m) {
  const auto groups = FaceGroups(m);
  Vec3 lo(1e300, 1e300, 1e300), hi(-1e300, -1e300, -1e300);
  for (const Vec3& p : m.nodes)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
  auto surface_tag = [](int32_t piece) { return piece < 0 ? 2 : 100 + piece; };
  std::string out = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n";
  absl::StrAppend(&out, 1 + groups.size(), "\n3 1 \"rock\"\n");
  for (const auto& [piece, faces] : groups) {
    absl::StrAppend(&out, "2 ", surface_tag(piece), " \"",
                    piece < 0 ? std::string("boundary") : absl::StrCat("sheet_", piece), "\"\n");
  }
  out += "$EndPhysicalNames\n$Entities\n";
  absl::StrAppend(&out, "0 0 ", groups.size(), " 1\n");
  for (const auto& [piece, faces] : groups) {
    absl::StrAppendFormat(&out, "%d %.12g %.12g %.12g %.12g %.12g %.12g 1 %d 0\n",
                          surface_tag(piece), lo.x, lo.y, lo.z, hi.x, hi.y, hi.z,
                          surface_tag(piece));
  }
  absl::StrAppendFormat(&out, "1 %.12g %.12g %.12g %.12g %.12g %.12g 1 1 0\n$EndEntities\n", lo.x,
                        lo.y, lo.z, hi.x, hi.y, hi.z);
  // All nodes in the volume's block; node tags are 1-based.
  absl::StrAppend(&out, "$Nodes\n1 ", m.nodes.size(), " 1 ", m.nodes.size(), "\n3 1 0 ",
                  m.nodes.size(), "\n");
  for (size_t i = 0; i < m.nodes.size(); ++i) absl::StrAppend(&out, i + 1, "\n");
  for (const Vec3& p : m.nodes) absl::StrAppendFormat(&out, "%.12g %.12g %.12g\n", p.x, p.y, p.z);
  out += "$EndNodes\n$Elements\n";
  const size_t total = m.tets.size() + m.faces.size();
  absl::StrAppend(&out, 1 + groups.size(), " ", total, " 1 ", total, "\n");
  size_t tag = 1;
  absl::StrAppend(&out, "3 1 4 ", m.tets.size(), "\n");
  for (const Tet& t : m.tets) {
    absl::StrAppend(&out, tag++, " ", t[0] + 1, " ", t[1] + 1, " ", t[2] + 1, " ", t[3] + 1, "\n");
  }
  for (const auto& [piece, faces] : groups) {
    absl::StrAppend(&out, "2 ", surface_tag(piece), " 2 ", faces.size(), "\n");
    for (size_t f : faces) {
      const auto& t = m.faces[f];
      absl::StrAppend(&out, tag++, " ", t[0] + 1, " ", t[1] + 1, " ", t[2] + 1, "\n");
    }
  }
  out += "$EndElements\n";
  return WriteFileAtomically(path, out);
}

absl::Status WriteAbaqus(const std::string& path, const TetMesh& m) {
  const auto groups = FaceGroups(m);
  std::string out = absl::StrCat("*HEADING\nsheetmesh ", SHEETMESH_VERSION,
                                 " volume mesh: rock tetrahedra with sheet faces\n*NODE\n");
  for (size_t i = 0; i < m.nodes.size(); ++i) {
    absl::StrAppendFormat(&out, "%d, %.12g, %.12g, %.12g\n", i + 1, m.nodes[i].x, m.nodes[i].y,
                          m.nodes[i].z);
  }
  out += "*ELEMENT, TYPE=C3D4, ELSET=ROCK\n";
  size_t id = 1;
  for (const Tet& t : m.tets) {
    absl::StrAppend(&out, id++, ", ", t[0] + 1, ", ", t[1] + 1, ", ", t[2] + 1, ", ", t[3] + 1,
                    "\n");
  }
  auto name = [](int32_t piece) {
    return piece < 0 ? std::string("BOUNDARY") : absl::StrCat("SHEET_", piece);
  };
  for (const auto& [piece, faces] : groups) {
    absl::StrAppend(&out, "*ELEMENT, TYPE=S3, ELSET=", name(piece), "\n");
    for (size_t f : faces) {
      const auto& t = m.faces[f];
      absl::StrAppend(&out, id++, ", ", t[0] + 1, ", ", t[1] + 1, ", ", t[2] + 1, "\n");
    }
  }
  // Surfaces on the tetrahedra's faces. C3D4 face numbering: S1 = (1,2,3), S2 = (1,4,2),
  // S3 = (2,4,3), S4 = (3,4,1).
  static const int kFace[4][3] = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {2, 3, 0}};
  absl::flat_hash_map<std::array<uint32_t, 3>, std::pair<size_t, int>> owner;
  for (size_t t = 0; t < m.tets.size(); ++t) {
    for (int k = 0; k < 4; ++k) {
      std::array<uint32_t, 3> key = {m.tets[t][kFace[k][0]], m.tets[t][kFace[k][1]],
                                     m.tets[t][kFace[k][2]]};
      std::sort(key.begin(), key.end());
      owner.emplace(key, std::make_pair(t + 1, k + 1));
    }
  }
  for (const auto& [piece, faces] : groups) {
    absl::StrAppend(&out, "*SURFACE, TYPE=ELEMENT, NAME=SURF_", name(piece), "\n");
    for (size_t f : faces) {
      std::array<uint32_t, 3> key = m.faces[f];
      std::sort(key.begin(), key.end());
      auto it = owner.find(key);
      if (it == owner.end()) {
        return absl::InternalError(absl::StrCat(path, ": face ", f, " belongs to no tetrahedron"));
      }
      absl::StrAppend(&out, it->second.first, ", S", it->second.second, "\n");
    }
  }
  return WriteFileAtomically(path, out);
}

}  // namespace sheetmesh
