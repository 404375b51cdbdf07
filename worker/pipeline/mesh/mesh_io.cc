#include "worker/pipeline/mesh/mesh_io.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "common/byte_order.h"
#include "common/file_util.h"
#include "common/status_macros.h"
#include "common/version.h"
#include "worker/pipeline/mesh/vtk_xml.h"

namespace sheetmesh {
namespace {}  // namespace

double PhysicalLength(double voxels, const Placement& p) {
  return voxels * std::cbrt(std::abs(p.spacing.x * p.spacing.y * p.spacing.z));
}

namespace {

// A face's colour for its thickness: blue (thinnest) through green to red (thickest) over
// [lo, hi], for readers that keep only colours (VTK's and ParaView's PLY reader).
std::array<int, 3> ThicknessColour(float t, float lo, float hi) {
  const double s = hi > lo ? std::clamp((t - lo) / (hi - lo), 0.0f, 1.0f) : 0.5;
  const double r = std::clamp(2 * s - 1, 0.0, 1.0), b = std::clamp(1 - 2 * s, 0.0, 1.0);
  const double g = 1 - r - b;
  return {static_cast<int>(std::lround(255 * r)), static_cast<int>(std::lround(255 * g)),
          static_cast<int>(std::lround(255 * b))};
}

}  // namespace

absl::Status WritePly(const std::string& path, const TriangleMesh& mesh,
                      const Placement& placement) {
  const bool vthick = mesh.vertex_thickness_voxels.size() == mesh.vertices.size();
  const bool fthick = mesh.face_thickness_voxels.size() == mesh.faces.size();
  const bool fpiece = mesh.face_piece.size() == mesh.faces.size();
  const bool faperture = fthick && mesh.face_aperture_voxels.size() == mesh.faces.size();
  std::string out =
      absl::StrCat("ply\nformat ascii 1.0\ncomment sheetmesh ", SHEETMESH_VERSION, "\n");
  if (!placement.unit.empty()) absl::StrAppend(&out, "comment unit ", placement.unit, "\n");
  if (fthick) out += "comment red, green, blue: thickness from blue (thinnest) to red\n";
  absl::StrAppend(&out, "element vertex ", mesh.vertices.size(),
                  "\nproperty float x\nproperty float y\nproperty float z\n");
  if (vthick) out += "property float thickness\n";
  // Which vertices are a body's (bodies and sheets share none): viewers that read no face
  // properties colour by it.
  std::vector<uint8_t> body_vertex;
  if (fpiece && !mesh.body_pieces.empty()) {
    body_vertex.assign(mesh.vertices.size(), 0);
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      if (mesh.IsBodyFace(f))
        for (uint32_t v : mesh.faces[f]) body_vertex[v] = 1;
    }
    out += "property uchar body\n";
  }
  absl::StrAppend(&out, "element face ", mesh.faces.size(),
                  "\nproperty list uchar int vertex_indices\n");
  if (fthick) out += "property float thickness\nproperty float thickness_voxels\n";
  if (faperture) out += "property float aperture\nproperty float aperture_voxels\n";
  if (fpiece) out += "property int piece\n";
  const bool fbody = fpiece && !mesh.body_pieces.empty();
  if (fbody) out += "property uchar body\n";
  if (fthick) out += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  out += "end_header\n";
  out.reserve(out.size() + mesh.vertices.size() * 40 + mesh.faces.size() * 48);
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    const Vec3 p = placement.ToPhysical(mesh.vertices[v]);
    absl::StrAppendFormat(&out, "%.9g %.9g %.9g", static_cast<float>(p.x), static_cast<float>(p.y),
                          static_cast<float>(p.z));
    if (vthick) {
      absl::StrAppendFormat(
          &out, " %.7g",
          static_cast<float>(PhysicalLength(mesh.vertex_thickness_voxels[v], placement)));
    }
    if (!body_vertex.empty()) out += body_vertex[v] ? " 1" : " 0";
    out += '\n';
  }
  float lo = 0, hi = 0;
  if (fthick && !mesh.faces.empty()) {
    const auto [mn, mx] =
        std::minmax_element(mesh.face_thickness_voxels.begin(), mesh.face_thickness_voxels.end());
    lo = *mn;
    hi = *mx;
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Face& t = mesh.faces[f];
    absl::StrAppend(&out, "3 ", t[0], " ", t[1], " ", t[2]);
    if (fthick) {
      absl::StrAppendFormat(
          &out, " %.7g %.7g",
          static_cast<float>(PhysicalLength(mesh.face_thickness_voxels[f], placement)),
          mesh.face_thickness_voxels[f]);
    }
    if (faperture) {
      absl::StrAppendFormat(
          &out, " %.7g %.7g",
          static_cast<float>(PhysicalLength(mesh.face_aperture_voxels[f], placement)),
          mesh.face_aperture_voxels[f]);
    }
    if (fpiece) absl::StrAppend(&out, " ", mesh.face_piece[f]);
    if (fbody) absl::StrAppend(&out, mesh.IsBodyFace(f) ? " 1" : " 0");
    if (fthick) {
      const std::array<int, 3> c = ThicknessColour(mesh.face_thickness_voxels[f], lo, hi);
      absl::StrAppend(&out, " ", c[0], " ", c[1], " ", c[2]);
    }
    out += '\n';
  }
  return WriteFileAtomically(path, out);
}

namespace {

// The surface as VTK XML: PolyData (.vtp) or UnstructuredGrid (.vtu, for readers such as
// meshio that take no PolyData), the same arrays in both.
std::string SurfaceVtkXml(const TriangleMesh& mesh, const Placement& placement, bool unstructured) {
  const size_t nf = mesh.faces.size();
  VtkXml vtk(unstructured ? VtkKind::kUnstructuredGrid : VtkKind::kPolyData, mesh.vertices.size(),
             nf);
  vtk.Points(
      mesh.vertices.size(), [&](size_t v) { return placement.ToPhysical(mesh.vertices[v]); }, 9);
  const auto physical = [&](const std::vector<float>& t) {
    return [&](size_t i) { return absl::StrFormat("%.7g", PhysicalLength(t[i], placement)); };
  };
  if (mesh.vertex_thickness_voxels.size() == mesh.vertices.size()) {
    vtk.BeginData("PointData", "thickness");
    vtk.Array("Float32", "thickness", mesh.vertices.size(), physical(mesh.vertex_thickness_voxels));
    vtk.EndData();
  }
  vtk.BeginData("CellData", "thickness");
  if (mesh.face_thickness_voxels.size() == nf) {
    vtk.Array("Float32", "thickness", nf, physical(mesh.face_thickness_voxels));
    vtk.Array("Float32", "thickness_voxels", nf,
              [&](size_t f) { return absl::StrFormat("%.7g", mesh.face_thickness_voxels[f]); });
  }
  if (mesh.face_aperture_voxels.size() == nf) {
    vtk.Array("Float32", "aperture", nf, physical(mesh.face_aperture_voxels));
  }
  if (mesh.face_piece.size() == nf) {
    vtk.Array("Int32", "piece", nf, [&](size_t f) { return mesh.face_piece[f]; });
    // 1 on a body's faces (the closed surface around a piece), 0 on a sheet's.
    vtk.Array("UInt8", "body", nf, [&](size_t f) { return mesh.IsBodyFace(f) ? 1 : 0; });
  }
  vtk.EndData();
  vtk.BeginCells();
  vtk.Array("Int64", "connectivity", nf, [&](size_t f) {
    return absl::StrCat(mesh.faces[f][0], " ", mesh.faces[f][1], " ", mesh.faces[f][2]);
  });
  vtk.Array("Int64", "offsets", nf, [](size_t f) { return 3 * (f + 1); });
  if (unstructured) vtk.Array("UInt8", "types", nf, [](size_t) { return 5; });  // VTK_TRIANGLE
  vtk.EndCells();
  return std::move(vtk).Finish();
}

}  // namespace

absl::Status WriteVtp(const std::string& path, const TriangleMesh& mesh,
                      const Placement& placement) {
  return WriteFileAtomically(path, SurfaceVtkXml(mesh, placement, /*unstructured=*/false));
}

absl::Status WriteSurfaceVtu(const std::string& path, const TriangleMesh& mesh,
                             const Placement& placement) {
  return WriteFileAtomically(path, SurfaceVtkXml(mesh, placement, /*unstructured=*/true));
}

absl::Status WriteObj(const std::string& path, const TriangleMesh& mesh,
                      const Placement& placement) {
  std::string out = absl::StrCat("# sheetmesh ", SHEETMESH_VERSION, ": ", mesh.vertices.size(),
                                 " vertices, ", mesh.faces.size(), " triangles\n");
  if (!placement.unit.empty()) absl::StrAppend(&out, "# unit ", placement.unit, "\n");
  for (const Vec3& v : mesh.vertices) {
    const Vec3 p = placement.ToPhysical(v);
    absl::StrAppendFormat(&out, "v %.9g %.9g %.9g\n", p.x, p.y, p.z);
  }
  // OBJ has no per-face values: the thickness at each vertex travels as its texture
  // coordinate (u physical, v in voxels), which meshio reads as point data "obj:vt".
  const bool vthick = mesh.vertex_thickness_voxels.size() == mesh.vertices.size();
  if (vthick) {
    out += "# vt u v: the thickness at the vertex (u physical, v in voxels)\n";
    for (float t : mesh.vertex_thickness_voxels)
      absl::StrAppendFormat(&out, "vt %.7g %.7g\n", PhysicalLength(t, placement), t);
  }
  const bool pieces = mesh.face_piece.size() == mesh.faces.size();
  std::vector<size_t> order(mesh.faces.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  if (pieces) {
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return mesh.face_piece[a] < mesh.face_piece[b]; });
  }
  int64_t group = INT64_MIN;
  for (size_t f : order) {
    if (pieces && mesh.face_piece[f] != group) {
      group = mesh.face_piece[f];
      absl::StrAppend(&out, "g piece_", group, "\n");
    }
    const Face& t = mesh.faces[f];
    if (vthick) {
      absl::StrAppend(&out, "f ", t[0] + 1, "/", t[0] + 1, " ", t[1] + 1, "/", t[1] + 1, " ",
                      t[2] + 1, "/", t[2] + 1, "\n");
    } else {
      absl::StrAppend(&out, "f ", t[0] + 1, " ", t[1] + 1, " ", t[2] + 1, "\n");
    }
  }
  return WriteFileAtomically(path, out);
}

namespace {

Vec3 ToIndex(const Vec3& p, const Placement& pl) {
  return {(p.x - pl.origin.x) / pl.spacing.x, (p.y - pl.origin.y) / pl.spacing.y,
          (p.z - pl.origin.z) / pl.spacing.z};
}

absl::Status AddPolygon(const std::vector<int64_t>& idx, size_t num_vertices,
                        const std::string& where, TriangleMesh* mesh) {
  for (int64_t i : idx) {
    if (i < 0 || static_cast<size_t>(i) >= num_vertices) {
      return absl::InvalidArgumentError(
          absl::StrCat(where, ": vertex index ", i, " outside 0..", num_vertices - 1));
    }
  }
  for (size_t k = 1; k + 1 < idx.size(); ++k) {
    mesh->faces.push_back({static_cast<uint32_t>(idx[0]), static_cast<uint32_t>(idx[k]),
                           static_cast<uint32_t>(idx[k + 1])});
  }
  return absl::OkStatus();
}

absl::StatusOr<TriangleMesh> ReadObj(const std::string& path, const std::string& text,
                                     const Placement& placement) {
  TriangleMesh mesh;
  std::vector<std::vector<int64_t>> polys;
  int line_no = 0;
  for (absl::string_view line : absl::StrSplit(text, '\n')) {
    ++line_no;
    std::vector<absl::string_view> tok =
        absl::StrSplit(line, absl::ByAnyChar(" \t\r"), absl::SkipEmpty());
    if (tok.empty()) continue;
    if (tok[0] == "v") {
      Vec3 p;
      if (tok.size() < 4 || !absl::SimpleAtod(tok[1], &p.x) || !absl::SimpleAtod(tok[2], &p.y) ||
          !absl::SimpleAtod(tok[3], &p.z)) {
        return absl::InvalidArgumentError(
            absl::StrCat(path, " line ", line_no, ": bad vertex '", line, "'"));
      }
      mesh.vertices.push_back(ToIndex(p, placement));
    } else if (tok[0] == "f") {
      std::vector<int64_t> idx;
      for (size_t k = 1; k < tok.size(); ++k) {
        int64_t i = 0;
        const absl::string_view first = tok[k].substr(0, tok[k].find('/'));
        if (!absl::SimpleAtoi(first, &i) || i == 0) {
          return absl::InvalidArgumentError(
              absl::StrCat(path, " line ", line_no, ": bad face '", line, "'"));
        }
        // Negative indices count back from the last vertex so far.
        idx.push_back(i > 0 ? i - 1 : static_cast<int64_t>(mesh.vertices.size()) + i);
      }
      if (idx.size() < 3) {
        return absl::InvalidArgumentError(
            absl::StrCat(path, " line ", line_no, ": face with fewer than 3 vertices"));
      }
      polys.push_back(std::move(idx));
    }
  }
  for (size_t k = 0; k < polys.size(); ++k) {
    SM_RETURN_IF_ERROR(
        AddPolygon(polys[k], mesh.vertices.size(), absl::StrCat(path, " face ", k), &mesh));
  }
  return mesh;
}

struct PlyProperty {
  std::string name;
  std::string type;        // scalar type, or the item type of a list
  std::string count_type;  // list count type; empty for scalars
};
struct PlyElement {
  std::string name;
  int64_t count = 0;
  std::vector<PlyProperty> props;
};

int TypeSize(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32")
    return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

// Reads binary scalars and ascii tokens behind one interface.
class PlyCursor {
 public:
  PlyCursor(const std::string& data, size_t pos, bool ascii, bool big)
      : data_(data), pos_(pos), ascii_(ascii), big_(big) {}

  bool Read(const std::string& type, double* out) {
    if (ascii_) {
      while (pos_ < data_.size() && absl::ascii_isspace(data_[pos_])) ++pos_;
      size_t end = pos_;
      while (end < data_.size() && !absl::ascii_isspace(data_[end])) ++end;
      if (end == pos_) return false;
      const bool ok = absl::SimpleAtod(absl::string_view(data_).substr(pos_, end - pos_), out);
      pos_ = end;
      return ok;
    }
    const int n = TypeSize(type);
    if (n == 0 || pos_ + n > data_.size()) return false;
    unsigned char b[8];
    std::memcpy(b, data_.data() + pos_, n);
    pos_ += n;
    if (big_ == NativeIsLittleEndian()) std::reverse(b, b + n);
    if (type == "char" || type == "int8")
      *out = static_cast<int8_t>(b[0]);
    else if (type == "uchar" || type == "uint8")
      *out = b[0];
    else if (type == "short" || type == "int16") {
      int16_t v;
      std::memcpy(&v, b, 2);
      *out = v;
    } else if (type == "ushort" || type == "uint16") {
      uint16_t v;
      std::memcpy(&v, b, 2);
      *out = v;
    } else if (type == "int" || type == "int32") {
      int32_t v;
      std::memcpy(&v, b, 4);
      *out = v;
    } else if (type == "uint" || type == "uint32") {
      uint32_t v;
      std::memcpy(&v, b, 4);
      *out = v;
    } else if (type == "float" || type == "float32") {
      float v;
      std::memcpy(&v, b, 4);
      *out = v;
    } else {
      double v;
      std::memcpy(&v, b, 8);
      *out = v;
    }
    return true;
  }

 private:
  const std::string& data_;
  size_t pos_;
  bool ascii_, big_;
};

absl::StatusOr<TriangleMesh> ReadPly(const std::string& path, const std::string& data,
                                     const Placement& placement) {
  const size_t end = data.find("end_header");
  if (data.rfind("ply", 0) != 0 || end == std::string::npos) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": not a PLY file (no 'ply' magic or 'end_header')"));
  }
  size_t body = data.find('\n', end);
  if (body == std::string::npos)
    return absl::InvalidArgumentError(absl::StrCat(path, ": header ends without a newline"));
  ++body;
  bool ascii = false, big = false;
  std::vector<PlyElement> elements;
  for (absl::string_view line : absl::StrSplit(absl::string_view(data).substr(0, end), '\n')) {
    std::vector<absl::string_view> tok =
        absl::StrSplit(line, absl::ByAnyChar(" \t\r"), absl::SkipEmpty());
    if (tok.empty()) continue;
    if (tok[0] == "format" && tok.size() >= 2) {
      ascii = tok[1] == "ascii";
      big = tok[1] == "binary_big_endian";
      if (!ascii && !big && tok[1] != "binary_little_endian") {
        return absl::InvalidArgumentError(
            absl::StrCat(path, ": PLY format '", tok[1], "' is unknown"));
      }
    } else if (tok[0] == "element" && tok.size() >= 3) {
      PlyElement e;
      e.name = std::string(tok[1]);
      if (!absl::SimpleAtoi(tok[2], &e.count) || e.count < 0) {
        return absl::InvalidArgumentError(
            absl::StrCat(path, ": element '", tok[1], "' count '", tok[2], "'"));
      }
      elements.push_back(e);
    } else if (tok[0] == "property" && !elements.empty()) {
      PlyProperty p;
      if (tok.size() >= 5 && tok[1] == "list") {
        p.count_type = std::string(tok[2]);
        p.type = std::string(tok[3]);
        p.name = std::string(tok[4]);
      } else if (tok.size() >= 3) {
        p.type = std::string(tok[1]);
        p.name = std::string(tok[2]);
      }
      if (TypeSize(p.type) == 0 || (!p.count_type.empty() && TypeSize(p.count_type) == 0)) {
        return absl::InvalidArgumentError(
            absl::StrCat(path, ": property '", line, "' has an unknown type"));
      }
      elements.back().props.push_back(p);
    }
  }
  TriangleMesh mesh;
  PlyCursor cur(data, body, ascii, big);
  const double unit = PhysicalLength(1.0, placement);
  std::vector<float> face_thick, face_thick_vox, face_aperture_vox, vert_thick;
  std::vector<bool> face_body;
  for (const PlyElement& e : elements) {
    for (int64_t i = 0; i < e.count; ++i) {
      Vec3 p;
      std::vector<int64_t> idx;
      for (const PlyProperty& prop : e.props) {
        double v = 0;
        if (prop.count_type.empty()) {
          if (!cur.Read(prop.type, &v)) {
            return absl::InvalidArgumentError(absl::StrCat(
                path, ": element ", e.name, " ", i, " property ", prop.name, " is truncated"));
          }
          if (e.name == "vertex") {
            if (prop.name == "x") p.x = v;
            if (prop.name == "y") p.y = v;
            if (prop.name == "z") p.z = v;
            if (prop.name == "thickness") vert_thick.push_back(static_cast<float>(v / unit));
          } else if (e.name == "face") {
            if (prop.name == "thickness") face_thick.push_back(static_cast<float>(v / unit));
            if (prop.name == "thickness_voxels") face_thick_vox.push_back(static_cast<float>(v));
            if (prop.name == "aperture_voxels") face_aperture_vox.push_back(static_cast<float>(v));
            if (prop.name == "piece") mesh.face_piece.push_back(static_cast<int32_t>(v));
            if (prop.name == "body") face_body.push_back(v != 0);
          }
          continue;
        }
        double n = 0;
        if (!cur.Read(prop.count_type, &n) || n < 0 || n > 1e6) {
          return absl::InvalidArgumentError(absl::StrCat(path, ": element ", e.name, " ", i,
                                                         " list ", prop.name, " has a bad count"));
        }
        for (int k = 0; k < static_cast<int>(n); ++k) {
          if (!cur.Read(prop.type, &v)) {
            return absl::InvalidArgumentError(absl::StrCat(path, ": element ", e.name, " ", i,
                                                           " list ", prop.name, " is truncated"));
          }
          if (e.name == "face" && (prop.name == "vertex_indices" || prop.name == "vertex_index")) {
            idx.push_back(static_cast<int64_t>(v));
          }
        }
      }
      if (e.name == "vertex") mesh.vertices.push_back(ToIndex(p, placement));
      if (e.name == "face") {
        if (idx.size() < 3) {
          return absl::InvalidArgumentError(
              absl::StrCat(path, ": face ", i, " has fewer than 3 vertices"));
        }
        if (idx.size() != 3 && (!face_thick.empty() || !face_thick_vox.empty())) {
          return absl::InvalidArgumentError(
              absl::StrCat(path, ": face ", i, " is not a triangle but carries a thickness"));
        }
        SM_RETURN_IF_ERROR(
            AddPolygon(idx, mesh.vertices.size(), absl::StrCat(path, " face ", i), &mesh));
      }
    }
  }
  // Attributes only count when every element has them.
  if (face_aperture_vox.size() == mesh.faces.size()) {
    mesh.face_aperture_voxels = std::move(face_aperture_vox);
  }
  if (face_thick_vox.size() == mesh.faces.size()) {
    mesh.face_thickness_voxels = std::move(face_thick_vox);
  } else if (face_thick.size() == mesh.faces.size()) {
    mesh.face_thickness_voxels = std::move(face_thick);
  }
  if (mesh.face_piece.size() != mesh.faces.size()) mesh.face_piece.clear();
  if (!mesh.face_piece.empty() && face_body.size() == mesh.faces.size()) {
    for (size_t f = 0; f < face_body.size(); ++f) {
      if (face_body[f]) mesh.body_pieces.push_back(mesh.face_piece[f]);
    }
    std::sort(mesh.body_pieces.begin(), mesh.body_pieces.end());
    mesh.body_pieces.erase(std::unique(mesh.body_pieces.begin(), mesh.body_pieces.end()),
                           mesh.body_pieces.end());
  }
  if (vert_thick.size() == mesh.vertices.size())
    mesh.vertex_thickness_voxels = std::move(vert_thick);
  return mesh;
}

}  // namespace

absl::StatusOr<TriangleMesh> ReadMesh(const std::string& path, const Placement& placement) {
  SM_ASSIGN_OR_RETURN(std::string data, ReadFileToString(path, int64_t{4} << 30));
  const std::string ext = absl::AsciiStrToLower(std::filesystem::path(path).extension().string());
  if (ext == ".ply") return ReadPly(path, data, placement);
  if (ext == ".obj") return ReadObj(path, data, placement);
  return absl::InvalidArgumentError(
      absl::StrCat(path, ": mesh format '", ext, "' is not readable; use .ply or .obj"));
}

}  // namespace sheetmesh
