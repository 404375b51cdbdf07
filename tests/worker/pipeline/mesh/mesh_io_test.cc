#include "worker/pipeline/mesh/mesh_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "common/file_util.h"
#include "tests/testing/status_matchers.h"
#include "tests/testing/temp_dir.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::IsOk;
using ::sheetmesh::testing::StatusIs;
using ::sheetmesh::testing::TempDir;
using ::testing::HasSubstr;

TriangleMesh Sample() {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {2, 2, 1}};
  m.faces = {{0, 1, 2}, {1, 3, 2}};
  m.face_thickness_voxels = {3.5f, 0.0f};
  m.face_piece = {4, 7};
  m.vertex_thickness_voxels = {1, 2, 3, 4};
  return m;
}

TEST(MeshIoTest, PlyRoundTripKeepsGeometryAndAttributesInPhysicalUnits) {
  TempDir tmp;
  Placement pl;
  pl.spacing = {0.5, 0.5, 0.5};
  pl.origin = {10, 20, 30};
  const std::string path = tmp.File("m.ply");
  ASSERT_THAT(WritePly(path, Sample(), pl), IsOk());
  SM_ASSERT_OK_AND_ASSIGN(TriangleMesh back, ReadMesh(path, pl));
  const TriangleMesh m = Sample();
  ASSERT_EQ(back.vertices.size(), 4u);
  for (size_t v = 0; v < 4; ++v) {
    EXPECT_NEAR(back.vertices[v].x, m.vertices[v].x, 1e-5);
    EXPECT_NEAR(back.vertices[v].z, m.vertices[v].z, 1e-5);
    EXPECT_NEAR(back.vertex_thickness_voxels[v], m.vertex_thickness_voxels[v], 1e-5);
  }
  EXPECT_EQ(back.faces, m.faces);
  EXPECT_EQ(back.face_thickness_voxels, m.face_thickness_voxels);
  EXPECT_EQ(back.face_piece, m.face_piece);
  // Physical coordinates in the file: vertex 1 is at 10 + 2 * 0.5 = 11.
  SM_ASSERT_OK_AND_ASSIGN(TriangleMesh phys, ReadMesh(path));
  EXPECT_NEAR(phys.vertices[1].x, 11.0, 1e-5);
}

TEST(MeshIoTest, PlyAndVtpCarryWhichPiecesAreBodies) {
  TempDir tmp;
  TriangleMesh m = Sample();
  m.body_pieces = {7};
  ASSERT_THAT(WritePly(tmp.File("m.ply"), m, {}), IsOk());
  SM_ASSERT_OK_AND_ASSIGN(TriangleMesh back, ReadMesh(tmp.File("m.ply")));
  EXPECT_EQ(back.body_pieces, std::vector<int32_t>{7});
  EXPECT_FALSE(back.IsBodyFace(0));
  EXPECT_TRUE(back.IsBodyFace(1));
  const std::string ply = *ReadFileToString(tmp.File("m.ply"));
  EXPECT_THAT(ply, HasSubstr("property uchar body\n"));
  ASSERT_THAT(WriteVtp(tmp.File("m.vtp"), m, {}), IsOk());
  EXPECT_THAT(*ReadFileToString(tmp.File("m.vtp")), HasSubstr("Name=\"body\""));
  // Without bodies, no body property.
  ASSERT_THAT(WritePly(tmp.File("s.ply"), Sample(), {}), IsOk());
  EXPECT_THAT(*ReadFileToString(tmp.File("s.ply")), ::testing::Not(HasSubstr("body")));
}

TEST(MeshIoTest, ObjAndAsciiPlyRead) {
  TempDir tmp;
  ASSERT_THAT(WriteObj(tmp.File("m.obj"), Sample(), {}), IsOk());
  SM_ASSERT_OK_AND_ASSIGN(TriangleMesh obj, ReadMesh(tmp.File("m.obj")));
  EXPECT_EQ(obj.vertices.size(), 4u);
  EXPECT_EQ(obj.faces.size(), 2u);
  ASSERT_THAT(WriteFileAtomically(tmp.File("a.ply"),
                                  "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\n"
                                  "property double y\nproperty double z\nelement face 1\n"
                                  "property list uchar int vertex_indices\nend_header\n"
                                  "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n"),
              IsOk());
  SM_ASSERT_OK_AND_ASSIGN(TriangleMesh quad, ReadMesh(tmp.File("a.ply")));
  EXPECT_EQ(quad.faces.size(), 2u) << "a quad is fanned into two triangles";
}

TEST(MeshIoTest, VtpNamesItsArrays) {
  TempDir tmp;
  ASSERT_THAT(WriteVtp(tmp.File("m.vtp"), Sample(), {}), IsOk());
  SM_ASSERT_OK_AND_ASSIGN(std::string text, ReadFileToString(tmp.File("m.vtp")));
  EXPECT_THAT(text, HasSubstr("NumberOfPoints=\"4\" NumberOfPolys=\"2\""));
  EXPECT_THAT(text, HasSubstr("Name=\"thickness\""));
  EXPECT_THAT(text, HasSubstr("Name=\"piece\""));
}

TEST(MeshIoTest, MalformedFilesNameWhatIsWrong) {
  TempDir tmp;
  ASSERT_THAT(WriteFileAtomically(tmp.File("bad.ply"),
                                  "ply\nformat ascii 1.0\nelement vertex 2\n"
                                  "property float x\nproperty float y\nproperty float z\n"
                                  "element face 1\nproperty list uchar int vertex_indices\n"
                                  "end_header\n0 0 0\n1 1 1\n3 0 1 9\n"),
              IsOk());
  EXPECT_THAT(ReadMesh(tmp.File("bad.ply")),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("vertex index 9")));
  ASSERT_THAT(WriteFileAtomically(tmp.File("trunc.ply"),
                                  "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
                                  "property float x\nend_header\n\x01\x02"),
              IsOk());
  EXPECT_THAT(ReadMesh(tmp.File("trunc.ply")),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("truncated")));
  ASSERT_THAT(WriteFileAtomically(tmp.File("bad.obj"), "v 0 0 0\nv 1 0\n"), IsOk());
  EXPECT_THAT(ReadMesh(tmp.File("bad.obj")),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("line 2")));
  EXPECT_THAT(ReadMesh(tmp.File("x.stl")), StatusIs(absl::StatusCode::kNotFound));
  ASSERT_THAT(WriteFileAtomically(tmp.File("x.stl"), "solid"), IsOk());
  EXPECT_THAT(ReadMesh(tmp.File("x.stl")),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr(".stl")));
}

}  // namespace
}  // namespace sheetmesh
