#include "worker/pipeline/mesh/decimate.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "tests/testing/meshes.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::Grid;

double TotalArea(const TriangleMesh& m) {
  double a = 0;
  for (size_t f = 0; f < m.num_faces(); ++f) a += Area(Corners(m, f));
  return a;
}

TEST(DecimateTest, APlaneRectangleNeedsOnlyItsOutline) {
  TriangleMesh m = Grid(12, 8, [](int x, int y) { return Vec3{double(x), double(y), 3.0}; });
  m.face_piece.assign(m.num_faces(), 7);
  const DecimateStats s = Decimate(&m, {.target_faces = 2});
  EXPECT_EQ(s.faces_before, 192u);
  EXPECT_LE(m.num_faces(), 8u);
  EXPECT_NEAR(TotalArea(m), 96.0, 1e-6);  // the rectangle whole
  for (const Vec3& v : m.vertices) {
    EXPECT_DOUBLE_EQ(v.z, 3.0);
    // The outline keeps its corners: every vertex is still on the rectangle's rim or inside.
    EXPECT_GE(v.x, 0.0);
    EXPECT_LE(v.x, 12.0);
  }
  EXPECT_THAT(m.face_piece, ::testing::Each(7));
  EXPECT_EQ(AnalyzeTopology(m).boundary_loops, 1u);
}

TEST(DecimateTest, AFoldIsKeptWhereTheFlatIsMerged) {
  // Two planes meeting at a right angle along x = 6.
  TriangleMesh m = Grid(12, 8, [](int x, int y) {
    return x <= 6 ? Vec3{double(x), double(y), 0} : Vec3{6, double(y), double(x - 6)};
  });
  Decimate(&m, {.target_faces = 4});
  ASSERT_GT(m.num_faces(), 0u);
  for (size_t f = 0; f < m.num_faces(); ++f) {
    const Vec3 n = UnitNormal(Corners(m, f));
    EXPECT_TRUE(std::abs(std::abs(n.z) - 1) < 1e-9 || std::abs(std::abs(n.x) - 1) < 1e-9)
        << "face " << f << " bridges the fold";
  }
  EXPECT_NEAR(TotalArea(m), 96.0, 1e-6);
}

TEST(DecimateTest, VerticesOfAJunctionStayAndTheTargetIsNotForced) {
  // A third sheet standing on the grid's middle row of edges: those edges have 3+ faces.
  TriangleMesh m = Grid(6, 6, [](int x, int y) { return Vec3{double(x), double(y), 0}; });
  const size_t base = m.vertices.size();
  for (int y = 0; y <= 6; ++y) m.vertices.push_back({3, double(y), 2});
  for (int y = 0; y < 6; ++y) {
    const uint32_t a = static_cast<uint32_t>(y * 7 + 3), b = static_cast<uint32_t>((y + 1) * 7 + 3);
    const uint32_t c = static_cast<uint32_t>(base + y), d = static_cast<uint32_t>(base + y + 1);
    m.faces.push_back({a, b, d});
    m.faces.push_back({a, d, c});
  }
  std::vector<Vec3> junction;
  for (int y = 0; y <= 6; ++y) junction.push_back({3, double(y), 0});
  Decimate(&m, {.target_faces = 1});
  for (const Vec3& j : junction) {
    EXPECT_TRUE(std::find(m.vertices.begin(), m.vertices.end(), j) != m.vertices.end())
        << "junction vertex " << j.y << " moved or went";
  }
  EXPECT_GT(m.num_faces(), 1u);
}

}  // namespace
}  // namespace sheetmesh
