#include "worker/pipeline/mesh/aperture_decimate.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "tests/testing/meshes.h"
#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::Grid;

// A flat sheet 3 voxels thick on a 24 x 16 grid: every collapse inside it costs nothing, so
// the quadric alone leaves whatever triangles the order of the collapses gives.
TriangleMesh FlatSheet() {
  TriangleMesh m = Grid(24, 16, [](int x, int y) { return Vec3{double(x), double(y), 5.0}; });
  m.vertex_thickness_voxels.assign(m.vertices.size(), 3.0f);
  m.face_piece.assign(m.num_faces(), 0);
  return m;
}

double SmallestAngle(const TriangleMesh& m) {
  double smallest = 180;
  for (size_t f = 0; f < m.num_faces(); ++f) {
    smallest = std::min(smallest, MinAngleDegrees(Corners(m, f)));
  }
  return smallest;
}

double TotalArea(const TriangleMesh& m) {
  double a = 0;
  for (size_t f = 0; f < m.num_faces(); ++f) a += Area(Corners(m, f));
  return a;
}

TEST(ApertureDecimateTest, WithAnAngleBoundAFlatSheetKeepsItsTrianglesShapedAndItsArea) {
  TriangleMesh free = FlatSheet(), shaped = FlatSheet();
  ApertureDecimateOptions o;
  o.triangles = 150;
  const ApertureDecimateStats a = DecimateWithAperture(&free, o);
  o.min_angle_degrees = 10;
  const ApertureDecimateStats b = DecimateWithAperture(&shaped, o);
  EXPECT_EQ(a.faces_before, 768u);
  EXPECT_LE(a.faces_after, 150u);
  EXPECT_LE(b.faces_after, 150u);
  EXPECT_EQ(b.unshaped_collapses, 0u);
  // Without the bound the collapses leave needles; with it, no angle under 10 degrees.
  EXPECT_LT(SmallestAngle(free), 10.0);
  EXPECT_GE(SmallestAngle(shaped), 10.0);
  EXPECT_NEAR(TotalArea(shaped), 24.0 * 16.0, 1e-6);
  for (const float t : shaped.face_thickness_voxels) EXPECT_FLOAT_EQ(t, 3.0f);
}

TEST(ApertureDecimateTest, ATargetTheBoundCannotReachIsReachedWithoutIt) {
  TriangleMesh m = FlatSheet();
  ApertureDecimateOptions o;
  o.triangles = 2;
  o.min_angle_degrees = 40;  // more than a long thin rectangle's few triangles can keep
  const ApertureDecimateStats s = DecimateWithAperture(&m, o);
  EXPECT_GT(s.unshaped_collapses, 0u);
  EXPECT_LE(m.num_faces(), 8u);
  EXPECT_NEAR(TotalArea(m), 24.0 * 16.0, 1e-6);
}

}  // namespace
}  // namespace sheetmesh
