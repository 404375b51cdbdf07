#include "worker/pipeline/mesh/vtk_xml.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace sheetmesh {
namespace {

using ::testing::HasSubstr;

TEST(VtkXmlTest, PolyDataHasPolysAndNoTypes) {
  VtkXml vtk(VtkKind::kPolyData, 3, 1);
  vtk.Points(
      3, [](size_t i) { return Vec3(double(i), 0.5, 1.0 / 3); }, 4);
  vtk.BeginData("CellData", "thickness");
  vtk.Array("Float32", "thickness", 1, [](size_t) { return 2.5; });
  vtk.EndData();
  vtk.BeginCells();
  vtk.Array("Int64", "connectivity", 1, [](size_t) { return "0 1 2"; });
  vtk.Array("Int64", "offsets", 1, [](size_t) { return 3; });
  vtk.EndCells();
  const std::string out = std::move(vtk).Finish();
  EXPECT_EQ(out.rfind("<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\"", 0), 0u) << out;
  EXPECT_THAT(out, HasSubstr("<Piece NumberOfPoints=\"3\" NumberOfPolys=\"1\">"));
  // Coordinates with the digits asked for.
  EXPECT_THAT(out, HasSubstr("\n2 0.5 0.3333\n"));
  EXPECT_THAT(out, HasSubstr("<CellData Scalars=\"thickness\">\n<DataArray type=\"Float32\" "
                             "Name=\"thickness\" format=\"ascii\">\n2.5\n</DataArray>\n"
                             "</CellData>\n<Polys>\n"));
  EXPECT_THAT(out, HasSubstr("</Polys>\n</Piece>\n</PolyData>\n</VTKFile>\n"));
  EXPECT_THAT(out, ::testing::Not(HasSubstr("Cells")));
}

TEST(VtkXmlTest, UnstructuredGridKeepsTheOrderOfItsSectionsAndItsComment) {
  VtkXml vtk(VtkKind::kUnstructuredGrid, 4, 2, "lengths in mm");
  vtk.Points(
      4, [](size_t i) { return Vec3(0.1 * i, 0, 0); }, 12);
  vtk.BeginCells();
  vtk.Array("UInt8", "types", 2, [](size_t i) { return i == 0 ? 10 : 5; });
  vtk.EndCells();
  vtk.BeginData("PointData", "thickness");
  vtk.Array("Float32", "thickness", 4, [](size_t i) { return i; });
  vtk.EndData();
  vtk.BeginData("CellData", "MaterialIDs");
  vtk.EndData();
  const std::string out = std::move(vtk).Finish();
  EXPECT_EQ(out.rfind("<?xml version=\"1.0\"?>\n<!-- lengths in mm -->\n<VTKFile type=\""
                      "UnstructuredGrid\"",
                      0),
            0u)
      << out;
  EXPECT_THAT(out, HasSubstr("NumberOfPoints=\"4\" NumberOfCells=\"2\""));
  EXPECT_THAT(out, HasSubstr("\n0.3 0 0\n"));
  const size_t cells = out.find("<Cells>"), points = out.find("<PointData"),
               cell_data = out.find("<CellData");
  EXPECT_LT(cells, points);
  EXPECT_LT(points, out.find("</PointData>"));
  EXPECT_LT(out.find("</PointData>"), cell_data);
  EXPECT_THAT(out, HasSubstr("<CellData Scalars=\"MaterialIDs\">\n</CellData>\n</Piece>"));
  EXPECT_THAT(out, HasSubstr("Name=\"types\" format=\"ascii\">\n10\n5\n</DataArray>"));
}

}  // namespace
}  // namespace sheetmesh
