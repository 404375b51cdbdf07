#include "worker/pipeline/tet/tet_mesh.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace sheetmesh {
namespace {

// One tetrahedron whose face 0 is a sheet triangle of piece 2, 3 voxels thick, and face 1
// on the box; voxels of 0.5 mm from the origin (1, 2, 3).
TetMesh OneTet() {
  TetMesh m;
  Placement p;
  p.spacing = {0.5, 0.5, 0.5};
  p.origin = {1, 2, 3};
  for (const Vec3& v : {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0), Vec3(0, 0, 4)}) {
    m.nodes.push_back(p.ToPhysical(v));
  }
  m.tets = {{0, 1, 2, 3}};
  m.faces = {{0, 1, 2}, {0, 1, 3}};
  m.face_marker = {10, 1};
  m.face_piece = {2, -1};
  m.face_thickness_voxels = {3.f, 0.f};
  m.voxel_length = 0.5;
  m.unit = "mm";
  return m;
}

TEST(TetMeshTest, ThicknessIsKeptInVoxelsAndGivenPhysicalOnAsking) {
  const TetMesh m = OneTet();
  EXPECT_FLOAT_EQ(m.FaceThickness(0), 1.5f);
  EXPECT_FLOAT_EQ(m.FaceThickness(1), 0.f);
  EXPECT_EQ(m.num_sheet_faces(), 1u);
  EXPECT_EQ(m.UnitsText(), "lengths in mm (a voxel is 0.5 mm)");
}

TEST(TetMeshTest, TheSheetSurfaceIsInVoxelsWithItsThickness) {
  const TetMesh m = OneTet();
  Placement p;
  p.spacing = {0.5, 0.5, 0.5};
  p.origin = {1, 2, 3};
  const TriangleMesh s = m.SheetSurface(p);
  ASSERT_EQ(s.faces.size(), 1u);
  ASSERT_EQ(s.vertices.size(), 3u);
  EXPECT_NEAR(s.vertices[s.faces[0][1]].x, 4.0, 1e-12);
  EXPECT_EQ(s.face_piece, std::vector<int32_t>{2});
  EXPECT_EQ(s.face_thickness_voxels, std::vector<float>{3.f});
}

TEST(TetMeshTest, UnitsSayWhatIsUnknown) {
  TetMesh m;
  EXPECT_EQ(m.UnitsText(), "lengths in voxels");
  m.voxel_length = 0.25;
  EXPECT_THAT(m.UnitsText(), ::testing::HasSubstr("not given; a voxel is 0.25"));
}

}  // namespace
}  // namespace sheetmesh
