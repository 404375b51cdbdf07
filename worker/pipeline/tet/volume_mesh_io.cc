#include "worker/pipeline/tet/volume_mesh_io.h"

#include <algorithm>
#include <map>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/file_util.h"
#include "common/version.h"
#include "worker/pipeline/mesh/vtk_xml.h"

namespace sheetmesh {
namespace {

std::string G7(double v) { return absl::StrFormat("%.7g", v); }

}  // namespace

std::vector<int> BoxSides(const TetMesh& m) {
  Vec3 lo(1e300, 1e300, 1e300), hi(-1e300, -1e300, -1e300);
  for (const Vec3& p : m.nodes)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
  std::vector<int> side(m.faces.size(), -1);
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (m.face_piece[f] >= 0) continue;
    for (int k = 0; k < 3 && side[f] < 0; ++k) {
      const double tol = 1e-9 * std::max(1.0, hi[k] - lo[k]);
      bool at_lo = true, at_hi = true;
      for (uint32_t v : m.faces[f]) {
        at_lo = at_lo && std::abs(m.nodes[v][k] - lo[k]) <= tol;
        at_hi = at_hi && std::abs(m.nodes[v][k] - hi[k]) <= tol;
      }
      if (at_lo) side[f] = 2 * k;
      if (at_hi) side[f] = 2 * k + 1;
    }
  }
  return side;
}

std::map<int32_t, std::vector<size_t>> FaceGroups(const TetMesh& m) {
  std::map<int32_t, std::vector<size_t>> groups;
  for (size_t f = 0; f < m.faces.size(); ++f) groups[m.face_piece[f]].push_back(f);
  return groups;
}

std::map<int32_t, std::vector<size_t>> SheetFacesByPiece(const TetMesh& m) {
  std::map<int32_t, std::vector<size_t>> groups;
  for (size_t f = 0; f < m.faces.size(); ++f)
    if (m.face_piece[f] >= 0 && !m.IsBody(m.face_piece[f])) groups[m.face_piece[f]].push_back(f);
  return groups;
}

absl::Status WriteVtu(const std::string& path, const TetMesh& m, const VolumeFields* fields) {
  const size_t nt = m.tets.size(), cells = nt + m.faces.size();
  VtkXml vtk(VtkKind::kUnstructuredGrid, m.nodes.size(), cells,
             absl::StrCat("sheetmesh ", SHEETMESH_VERSION, ": ", m.UnitsText()));
  vtk.Points(
      m.nodes.size(), [&](size_t i) { return m.nodes[i]; }, 12);
  vtk.BeginCells();
  vtk.Array("Int64", "connectivity", cells, [&](size_t i) {
    if (i < nt) {
      const Tet& t = m.tets[i];
      return absl::StrCat(t[0], " ", t[1], " ", t[2], " ", t[3]);
    }
    const auto& f = m.faces[i - nt];
    return absl::StrCat(f[0], " ", f[1], " ", f[2]);
  });
  vtk.Array("Int64", "offsets", cells,
            [&](size_t i) { return i < nt ? 4 * (i + 1) : 4 * nt + 3 * (i - nt + 1); });
  // VTK_TETRA, VTK_TRIANGLE
  vtk.Array("UInt8", "types", cells, [&](size_t i) { return i < nt ? 10 : 5; });
  vtk.EndCells();
  vtk.BeginData("CellData", "MaterialIDs");
  int32_t top_piece = -1;
  for (int32_t p : m.face_piece) top_piece = std::max(top_piece, p);
  const int32_t box_id = top_piece + 2;
  // One value per cell: tet(t) on the tetrahedra, then face(f) on the faces.
  const auto cell_array = [&](const char* type, const char* name, auto tet, auto face) {
    vtk.Array(type, name, cells,
              [&](size_t i) { return i < nt ? absl::StrCat(tet(i)) : absl::StrCat(face(i - nt)); });
  };
  const auto zero = [](size_t) { return 0; };
  cell_array("Int32", "kind", zero, [&](size_t f) {
    return m.face_piece[f] < 0 ? 2 : (m.IsBody(m.face_piece[f]) ? 3 : 1);
  });
  cell_array(
      "Int32", "piece", [&](size_t t) { return m.Region(t); },
      [&](size_t f) { return m.face_piece[f]; });
  cell_array(
      "Int32", "MaterialIDs", [&](size_t t) { return m.Region(t) + 1; },
      [&](size_t f) { return m.face_piece[f] >= 0 ? m.face_piece[f] + 1 : box_id; });
  cell_array("Float32", "thickness", zero, [&](size_t f) { return G7(m.FaceThickness(f)); });
  cell_array("Float32", "thickness_voxels", zero,
             [&](size_t f) { return G7(m.face_thickness_voxels[f]); });
  cell_array("Float32", "aperture", zero, [&](size_t f) { return G7(m.FaceThickness(f)); });
  cell_array("Float64", "permeability", zero, [&](size_t f) {
    const double a = m.FaceThickness(f);
    return absl::StrFormat("%.9g", a * a / 12);
  });
  cell_array("Float64", "transmissivity", zero, [&](size_t f) {
    const double a = m.FaceThickness(f);
    return absl::StrFormat("%.9g", a * a * a / 12);
  });
  if (fields != nullptr) {
    for (const auto& [name, v] : fields->cell_vectors) {
      if (v.size() != cells) {
        return absl::InternalError(absl::StrCat("volume field ", name, " has ", v.size(),
                                                " values for ", cells, " cells"));
      }
      vtk.VectorArray(
          "Float64", name, cells, [&](size_t i) { return v[i]; }, 9);
    }
  }
  vtk.EndData();
  if (fields != nullptr && !fields->node_scalars.empty()) {
    vtk.BeginData("PointData", fields->node_scalars[0].first);
    for (const auto& [name, v] : fields->node_scalars) {
      if (v.size() != m.nodes.size()) {
        return absl::InternalError(absl::StrCat("volume field ", name, " has ", v.size(),
                                                " values for ", m.nodes.size(), " nodes"));
      }
      vtk.Array("Float64", name, v.size(), [&](size_t i) { return absl::StrFormat("%.9g", v[i]); });
    }
    vtk.EndData();
  }
  const std::string out = std::move(vtk).Finish();
  return WriteFileAtomically(path, out);
}

absl::Status WriteGmsh(const std::string& path, const TetMesh& m) {
  const auto groups = FaceGroups(m);
  std::map<int32_t, std::vector<size_t>> regions;  // -1 = the rock, p = body piece p
  for (size_t t = 0; t < m.tets.size(); ++t) regions[m.Region(t)].push_back(t);
  if (regions.empty()) regions[-1];
  Vec3 lo(1e300, 1e300, 1e300), hi(-1e300, -1e300, -1e300);
  for (const Vec3& p : m.nodes)
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[k]);
      hi[k] = std::max(hi[k], p[k]);
    }
  auto surface_tag = [](int32_t piece) { return piece < 0 ? 2 : 100 + piece; };
  auto volume_tag = [](int32_t piece) { return piece < 0 ? 1 : 100 + piece; };
  auto surface_name = [&](int32_t piece) {
    if (piece < 0) return std::string("boundary");
    return absl::StrCat(m.IsBody(piece) ? "body_" : "sheet_", piece,
                        m.IsBody(piece) ? "_wall" : "");
  };
  // A section readers skip (Gmsh and meshio pass over sections they do not know).
  std::string out =
      absl::StrCat("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Comments\nsheetmesh ", SHEETMESH_VERSION,
                   ": ", m.UnitsText(), "\n$EndComments\n$PhysicalNames\n");
  absl::StrAppend(&out, regions.size() + groups.size(), "\n");
  for (const auto& [piece, tets] : regions) {
    absl::StrAppend(&out, "3 ", volume_tag(piece), " \"",
                    piece < 0 ? std::string("rock") : absl::StrCat("body_", piece), "\"\n");
  }
  for (const auto& [piece, faces] : groups) {
    absl::StrAppend(&out, "2 ", surface_tag(piece), " \"", surface_name(piece), "\"\n");
  }
  out += "$EndPhysicalNames\n$Entities\n";
  absl::StrAppend(&out, "0 0 ", groups.size(), " ", regions.size(), "\n");
  for (const auto& [piece, faces] : groups) {
    absl::StrAppendFormat(&out, "%d %.12g %.12g %.12g %.12g %.12g %.12g 1 %d 0\n",
                          surface_tag(piece), lo.x, lo.y, lo.z, hi.x, hi.y, hi.z,
                          surface_tag(piece));
  }
  for (const auto& [piece, tets] : regions) {
    absl::StrAppendFormat(&out, "%d %.12g %.12g %.12g %.12g %.12g %.12g 1 %d 0\n",
                          volume_tag(piece), lo.x, lo.y, lo.z, hi.x, hi.y, hi.z, volume_tag(piece));
  }
  out += "$EndEntities\n";
  // All nodes in the rock's block; node tags are 1-based.
  absl::StrAppend(&out, "$Nodes\n1 ", m.nodes.size(), " 1 ", m.nodes.size(), "\n3 ",
                  volume_tag(regions.begin()->first), " 0 ", m.nodes.size(), "\n");
  for (size_t i = 0; i < m.nodes.size(); ++i) absl::StrAppend(&out, i + 1, "\n");
  for (const Vec3& p : m.nodes) absl::StrAppendFormat(&out, "%.12g %.12g %.12g\n", p.x, p.y, p.z);
  out += "$EndNodes\n$Elements\n";
  const size_t total = m.tets.size() + m.faces.size();
  absl::StrAppend(&out, regions.size() + groups.size(), " ", total, " 1 ", total, "\n");
  size_t tag = 1;
  for (const auto& [piece, tets] : regions) {
    absl::StrAppend(&out, "3 ", volume_tag(piece), " 4 ", tets.size(), "\n");
    for (size_t i : tets) {
      const Tet& t = m.tets[i];
      absl::StrAppend(&out, tag++, " ", t[0] + 1, " ", t[1] + 1, " ", t[2] + 1, " ", t[3] + 1,
                      "\n");
    }
  }
  for (const auto& [piece, faces] : groups) {
    absl::StrAppend(&out, "2 ", surface_tag(piece), " 2 ", faces.size(), "\n");
    for (size_t f : faces) {
      const auto& t = m.faces[f];
      absl::StrAppend(&out, tag++, " ", t[0] + 1, " ", t[1] + 1, " ", t[2] + 1, "\n");
    }
  }
  out += "$EndElements\n";
  // The thickness of every element (meshio takes element data only when every element has
  // it): 0 on the tetrahedra and the box, the sheet's on its triangles. Tags follow the
  // order written above.
  std::vector<double> thickness(total, 0.0), thickness_voxels(total, 0.0);
  tag = m.tets.size();
  for (const auto& [piece, faces] : groups) {
    for (size_t f : faces) {
      thickness[tag] = m.FaceThickness(f);
      thickness_voxels[tag++] = m.face_thickness_voxels[f];
    }
  }
  for (const bool voxels : {false, true}) {
    absl::StrAppend(&out, "$ElementData\n1\n\"", voxels ? "thickness_voxels" : "thickness",
                    "\"\n1\n0\n3\n0\n1\n", total, "\n");
    for (size_t e = 0; e < total; ++e)
      absl::StrAppendFormat(&out, "%d %.7g\n", e + 1, voxels ? thickness_voxels[e] : thickness[e]);
    out += "$EndElementData\n";
  }
  return WriteFileAtomically(path, out);
}

}  // namespace sheetmesh
