#include "worker/pipeline/mesh/vtk_xml.h"

#include <utility>

namespace sheetmesh {
namespace {

const char* Name(VtkKind kind) {
  return kind == VtkKind::kPolyData ? "PolyData" : "UnstructuredGrid";
}

}  // namespace

VtkXml::VtkXml(VtkKind kind, size_t points, size_t cells, absl::string_view comment) : kind_(kind) {
  out_ = "<?xml version=\"1.0\"?>\n";
  if (!comment.empty()) absl::StrAppend(&out_, "<!-- ", comment, " -->\n");
  absl::StrAppend(
      &out_, "<VTKFile type=\"", Name(kind), "\" version=\"1.0\" byte_order=\"LittleEndian\">\n<",
      Name(kind), ">\n<Piece NumberOfPoints=\"", points,
      kind == VtkKind::kPolyData ? "\" NumberOfPolys=\"" : "\" NumberOfCells=\"", cells, "\">\n");
}

void VtkXml::BeginData(absl::string_view section, absl::string_view scalars) {
  absl::StrAppend(&out_, "<", section, " Scalars=\"", scalars, "\">\n");
  data_ = std::string(section);
}

void VtkXml::EndData() {
  absl::StrAppend(&out_, "</", data_, ">\n");
  data_.clear();
}

void VtkXml::BeginCells() { out_ += kind_ == VtkKind::kPolyData ? "<Polys>\n" : "<Cells>\n"; }

void VtkXml::EndCells() { out_ += kind_ == VtkKind::kPolyData ? "</Polys>\n" : "</Cells>\n"; }

std::string VtkXml::Finish() && {
  absl::StrAppend(&out_, "</Piece>\n</", Name(kind_), ">\n</VTKFile>\n");
  return std::move(out_);
}

}  // namespace sheetmesh
