// Untangle: clashing sheet triangles mended by small moves and flips, every triangle kept.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/plc_parts.h"

namespace sheetmesh {
namespace {

SheetTriangles Sheets(const std::vector<Face>& faces, const std::vector<int32_t>& piece) {
  SheetTriangles s;
  s.faces = faces;
  for (uint32_t f = 0; f < faces.size(); ++f) {
    s.source.push_back(f);
    s.piece.push_back(piece[f]);
    s.thickness.push_back(2);
  }
  return s;
}

size_t Clashes(const SheetTriangles& s, const std::vector<Vec3>& v) {
  TriangleMesh m;
  m.vertices = v;
  m.faces = s.faces;
  return FindSelfIntersections(m, 1000, 1.0).size();
}

TEST(PlcUntangleTest, AFanFoldedOverItselfAtAVertexIsMendedByAMove) {
  // A fan of 6 triangles around c in the plane z = 5; rim vertex 2 pushed a little past
  // vertex 3, so that the triangle (c, 2, 3) turns over onto its neighbours.
  std::vector<Vec3> v = {{10, 10, 5}};  // c
  for (int k = 0; k < 6; ++k) {
    const double a = k * M_PI / 3;
    v.push_back({10 + 4 * std::cos(a), 10 + 4 * std::sin(a), 5});
  }
  v[2] = {10 + 4 * std::cos(2.1), 10 + 4 * std::sin(2.1), 5};  // 0.4 voxels past vertex 3
  v[3] = {10 + 4 * std::cos(2.0), 10 + 4 * std::sin(2.0), 5};
  std::vector<Face> faces;
  for (uint32_t k = 0; k < 6; ++k) faces.push_back({0, 1 + k, 1 + (k + 1) % 6});
  SheetTriangles s = Sheets(faces, std::vector<int32_t>(6, 0));
  ASSERT_GT(Clashes(s, v), 0u);
  const std::vector<uint8_t> on_face(v.size(), 0);
  const UntangleStats u = Untangle(s, v, on_face, 1.0);
  EXPECT_GT(u.found_pairs, 0u);
  EXPECT_EQ(u.remaining_pairs, 0u);
  EXPECT_GE(u.moved_vertices + u.flipped_edges, 1u);
  EXPECT_LE(u.max_move, 1.0);
  EXPECT_EQ(s.faces.size(), 6u) << "every triangle kept";
  EXPECT_EQ(Clashes(s, v), 0u);
}

TEST(PlcUntangleTest, ASheetPokingAFractionOfAVoxelThroughAnotherIsMended) {
  // Sheet B: a square in z = 5. Sheet A: a triangle standing on B's edge region whose
  // lower corner dips 0.3 voxels through B, away from B's vertices.
  std::vector<Vec3> v = {{0, 0, 5},    {20, 0, 5},  {20, 20, 5}, {0, 20, 5},  // B
                         {9, 10, 4.7}, {11, 8, 12}, {11, 12, 12}};            // A
  SheetTriangles s = Sheets({{0, 1, 2}, {0, 2, 3}, {4, 5, 6}}, {0, 0, 1});
  ASSERT_GT(Clashes(s, v), 0u);
  const std::vector<uint8_t> on_face(v.size(), 0);
  const UntangleStats u = Untangle(s, v, on_face, 1.0);
  EXPECT_EQ(u.remaining_pairs, 0u);
  EXPECT_EQ(Clashes(s, v), 0u);
  EXPECT_EQ(s.faces.size(), 3u);
  EXPECT_GT(v[4].z, 5.0) << "A's corner came back above B";
}

TEST(PlcUntangleTest, SheetsCrossingDeeplyAreSplitToMeetAlongTheirCrossing) {
  // Two squares crossing at right angles through each other's middles: no move of a voxel
  // undoes that, and none is made; the triangles are split along the crossing so that the
  // sheets meet in edges there, as crossing sheets must, every vertex where it was.
  std::vector<Vec3> v = {{0, 10, 0}, {20, 10, 0}, {20, 10, 20}, {0, 10, 20},
                         {10, 0, 0}, {10, 20, 0}, {10, 20, 20}, {10, 0, 20}};
  SheetTriangles s = Sheets({{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}}, {0, 0, 1, 1});
  const std::vector<Vec3> before = v;
  double area = 0;
  for (const Face& f : s.faces) area += Area({v[f[0]], v[f[1]], v[f[2]]});
  const std::vector<uint8_t> on_face(v.size(), 0);
  const UntangleStats u = Untangle(s, v, on_face, 1.0);
  EXPECT_EQ(u.remaining_pairs, 0u);
  EXPECT_EQ(u.moved_vertices, 0u);
  EXPECT_GE(u.split_crossings, 1u);
  EXPECT_EQ(Clashes(s, v), 0u);
  for (size_t i = 0; i < before.size(); ++i) EXPECT_EQ(v[i], before[i]) << i;
  for (size_t i = before.size(); i < v.size(); ++i) {
    EXPECT_NEAR(v[i].x, 10.0, 1e-9) << "a new vertex lies on the crossing line x = 10, y = 10";
    EXPECT_NEAR(v[i].y, 10.0, 1e-9);
  }
  double after = 0;
  for (const Face& f : s.faces) after += Area({v[f[0]], v[f[1]], v[f[2]]});
  EXPECT_NEAR(after, area, 1e-9);
}

TEST(PlcUntangleTest, AVertexOnABoxFaceStaysOnIt) {
  // The poking corner lies on the box face x = -0.5 (bit 0): it may move only in y and z.
  std::vector<Vec3> v = {{-0.5, 0, 5},    {20, 0, 5}, {20, 20, 5}, {-0.5, 20, 5},
                         {-0.5, 10, 4.7}, {4, 8, 12}, {4, 12, 12}};
  SheetTriangles s = Sheets({{0, 1, 2}, {0, 2, 3}, {4, 5, 6}}, {0, 0, 1});
  std::vector<uint8_t> on_face(v.size(), 0);
  on_face[0] = on_face[3] = on_face[4] = 1;
  const UntangleStats u = Untangle(s, v, on_face, 1.0);
  EXPECT_EQ(u.remaining_pairs, 0u);
  EXPECT_EQ(v[4].x, -0.5);
  EXPECT_EQ(Clashes(s, v), 0u);
}

}  // namespace
}  // namespace sheetmesh

namespace sheetmesh {
namespace {

TEST(PlcUntangleTest, TwoTrianglesCrossingBeyondASharedCornerAreSplitToMeetInAnEdge) {
  // Two triangles sharing p = (0, 0, 0), in planes 60 degrees apart, crossing along the
  // x axis for 6 voxels: no small move undoes that; both are split at the crossing's end
  // q = (6, 0, 0) (B's edge there, A around it) and meet in the edge p-q.
  std::vector<Vec3> v = {{0, 0, 0},
                         {10, -4, 0},
                         {10, 4, 0},  // A, in z = 0
                         {6, -3, -5.2},
                         {6, 3, 5.2}};  // B, tilted about x
  SheetTriangles s = Sheets({{0, 1, 2}, {0, 3, 4}}, {0, 1});
  ASSERT_EQ(Clashes(s, v), 1u);
  const std::vector<uint8_t> on_face(v.size(), 0);
  const UntangleStats u = Untangle(s, v, on_face, 0.5);
  EXPECT_EQ(u.remaining_pairs, 0u);
  EXPECT_EQ(u.split_crossings, 1u);
  EXPECT_EQ(Clashes(s, v), 0u);
  EXPECT_EQ(s.faces.size(), 2u + 1u + 2u) << "A in three around q, B in two along its edge";
  ASSERT_EQ(v.size(), 6u);
  EXPECT_NEAR(Norm(v[5] - Vec3(6, 0, 0)), 0.0, 1e-9);
  // The pieces cover what the two covered.
  double area = 0;
  for (const Face& f : s.faces) area += Area({v[f[0]], v[f[1]], v[f[2]]});
  EXPECT_NEAR(area, Area({v[0], v[1], v[2]}) + Area({v[0], v[3], v[4]}), 1e-9);
}

TEST(PlcUntangleTest, VerticesLyingOnAnotherSheetsEdgeOrFaceAreJoinedToThem) {
  // Sheet A, a square in z = 10 split along its diagonal 0-2; sheet B's vertex 4 lies on
  // that diagonal (a quarter along), sheet C's vertex 7 inside A's triangle (0, 1, 2),
  // neither joined to A: TetGen takes such a T for a crossing and aborts (the rough network
  // at r = 2). A's faces split there; nothing moves.
  std::vector<Vec3> v = {{2, 2, 10},  {22, 2, 10}, {22, 22, 10}, {2, 22, 10},  // A
                         {7, 7, 10},  {12, 4, 18}, {4, 12, 18},                // B
                         {18, 6, 10}, {18, 6, 18}, {14, 2, 16}};               // C
  SheetTriangles s = Sheets({{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {7, 8, 9}}, {0, 0, 1, 2});
  const std::vector<Vec3> before = v;
  EXPECT_EQ(JoinTouches(s, v, 1e-6), 2u);
  for (size_t i = 0; i < v.size(); ++i) EXPECT_LT(Norm(v[i] - before[i]), 1e-9) << i;
  // The diagonal's two faces split at 4 (4 faces), the half that holds 7 at 7 (3 faces):
  // 6 faces of A, B's and C's.
  ASSERT_EQ(s.faces.size(), 8u);
  auto has_edge = [&](uint32_t a, uint32_t b) {
    for (const Face& t : s.faces) {
      for (int k = 0; k < 3; ++k) {
        if ((t[k] == a && t[(k + 1) % 3] == b) || (t[k] == b && t[(k + 1) % 3] == a)) return true;
      }
    }
    return false;
  };
  EXPECT_TRUE(has_edge(0, 4));
  EXPECT_TRUE(has_edge(4, 2));
  EXPECT_FALSE(has_edge(0, 2));
  EXPECT_TRUE(has_edge(7, 1));
  // A keeps its area; pieces go with the faces.
  double area = 0;
  for (size_t f = 0; f < s.faces.size(); ++f) {
    if (s.piece[f] == 0) area += Area({v[s.faces[f][0]], v[s.faces[f][1]], v[s.faces[f][2]]});
  }
  EXPECT_NEAR(area, 400, 1e-9);
  EXPECT_EQ(JoinTouches(s, v, 1e-6), 0u);  // nothing left to join
}

TEST(PlcUntangleTest, AFlatTriangleLeftByTheMendsGoesAndItsCornerIsJoined) {
  // Triangle (0, 1, 2) has its corner 2 on its own long edge 0-1 (no area), as a split can
  // leave it (the rough network at r = 2); triangle (0, 3, 1) lies across that edge. The
  // flat one goes; 2 is then a T on the edge 0-1 of the other, which is joined.
  std::vector<Vec3> v = {{2, 2, 10}, {10, 2, 10}, {4, 2, 10}, {6, 8, 10}, {4, -4, 14}};
  SheetTriangles s = Sheets({{0, 1, 2}, {0, 3, 1}, {2, 4, 0}}, {0, 0, 0});
  EXPECT_EQ(DropFlatTriangles(s, v, 1e-6), 1u);
  ASSERT_EQ(s.faces.size(), 2u);
  EXPECT_EQ(DropFlatTriangles(s, v, 1e-6), 0u);
  EXPECT_EQ(JoinTouches(s, v, 1e-6), 1u);
  EXPECT_EQ(s.faces.size(), 3u);  // (0, 3, 1) split at 2 into two
  EXPECT_EQ(Clashes(s, v), 0u);
}

}  // namespace
}  // namespace sheetmesh
