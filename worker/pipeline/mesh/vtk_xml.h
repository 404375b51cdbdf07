// VTK XML files in ASCII (PolyData .vtp, UnstructuredGrid .vtu): the one writer of the
// format's framing, which the surface and the volume mesh writers fill with their arrays.
// Sections come out in the order they are called, one piece per file.
#ifndef SHEETMESH_WORKER_PIPELINE_MESH_VTK_XML_H_
#define SHEETMESH_WORKER_PIPELINE_MESH_VTK_XML_H_

#include <cstddef>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/string_view.h"
#include "common/types.h"

namespace sheetmesh {

enum class VtkKind {
  kPolyData,          // cells are polygons (<Polys>), no types array
  kUnstructuredGrid,  // cells of any type (<Cells>), with a types array
};

class VtkXml {
 public:
  // The header through <Piece>: `points` and `cells` counted, `comment` (without the
  // comment marks; "" for none) after the XML declaration.
  VtkXml(VtkKind kind, size_t points, size_t cells, absl::string_view comment = "");

  // <Points>: point(i) for i < count, each coordinate with `digits` significant digits.
  template <class P>
  void Points(size_t count, P point, int digits) {
    out_ += "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    for (size_t i = 0; i < count; ++i) {
      const Vec3 p = point(i);
      absl::StrAppendFormat(&out_, "%.*g %.*g %.*g\n", digits, p.x, digits, p.y, digits, p.z);
    }
    out_ += "</DataArray>\n</Points>\n";
  }

  // <PointData> or <CellData> (`section`), its default scalars named.
  void BeginData(absl::string_view section, absl::string_view scalars);
  void EndData();
  // <Polys> or <Cells>, as the kind has them.
  void BeginCells();
  void EndCells();

  // One array of `type` ("Float32", "Int64", ...): value(i) for i < count, one per line
  // (anything absl::StrAppend takes).
  template <class V>
  void Array(absl::string_view type, absl::string_view name, size_t count, V value) {
    absl::StrAppend(&out_, "<DataArray type=\"", type, "\" Name=\"", name,
                    "\" format=\"ascii\">\n");
    for (size_t i = 0; i < count; ++i) absl::StrAppend(&out_, value(i), "\n");
    out_ += "</DataArray>\n";
  }

  // An array of 3-vectors of `type`: value(i) (a Vec3) for i < count, `digits` significant
  // digits.
  template <class V>
  void VectorArray(absl::string_view type, absl::string_view name, size_t count, V value,
                   int digits) {
    absl::StrAppend(&out_, "<DataArray type=\"", type, "\" Name=\"", name,
                    "\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    for (size_t i = 0; i < count; ++i) {
      const Vec3 v = value(i);
      absl::StrAppendFormat(&out_, "%.*g %.*g %.*g\n", digits, v.x, digits, v.y, digits, v.z);
    }
    out_ += "</DataArray>\n";
  }

  // Closes the piece and the file; the text.
  std::string Finish() &&;

 private:
  VtkKind kind_;
  std::string out_;
  std::string data_;  // the data section open, to close
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_MESH_VTK_XML_H_
