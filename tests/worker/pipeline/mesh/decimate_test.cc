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
  const DecimateStats s = Decimate(&m, {.triangles = 2});
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
  Decimate(&m, {.triangles = 4});
  ASSERT_GT(m.num_faces(), 0u);
  for (size_t f = 0; f < m.num_faces(); ++f) {
    const Vec3 n = UnitNormal(Corners(m, f));
    EXPECT_TRUE(std::abs(std::abs(n.z) - 1) < 1e-9 || std::abs(std::abs(n.x) - 1) < 1e-9)
        << "face " << f << " bridges the fold";
  }
  EXPECT_NEAR(TotalArea(m), 96.0, 1e-6);
}

TEST(DecimateTest, AJunctionKeepsItsLineAndItsEnds) {
  // A third sheet standing on the grid's middle row of edges: those edges have 3 faces.
  TriangleMesh m = Grid(6, 6, [](int x, int y) { return Vec3{double(x), double(y), 0}; });
  const size_t base = m.vertices.size();
  for (int y = 0; y <= 6; ++y) m.vertices.push_back({3, double(y), 2});
  for (int y = 0; y < 6; ++y) {
    const uint32_t a = static_cast<uint32_t>(y * 7 + 3), b = static_cast<uint32_t>((y + 1) * 7 + 3);
    const uint32_t c = static_cast<uint32_t>(base + y), d = static_cast<uint32_t>(base + y + 1);
    m.faces.push_back({a, b, d});
    m.faces.push_back({a, d, c});
  }
  // Only the collapses that cost nothing: the inner vertices of the junction slide along it,
  // its ends (on the rim) stay, and the base becomes two rectangles of two triangles each
  // beside the standing sheet's two (a locked junction kept 44 faces).
  Decimate(&m, {.triangles = 1, .max_error = 1e-9});
  EXPECT_LE(m.num_faces(), 10u);
  EXPECT_NEAR(TotalArea(m), 36.0 + 12.0, 1e-6);
  for (const Vec3 end : {Vec3{3, 0, 0}, Vec3{3, 6, 0}}) {
    EXPECT_TRUE(std::find(m.vertices.begin(), m.vertices.end(), end) != m.vertices.end())
        << "junction end at y = " << end.y << " moved or went";
  }
  const TopologyReport t = AnalyzeTopology(m);
  EXPECT_GE(t.nonmanifold_edges, 1u);
  EXPECT_EQ(t.duplicate_faces, 0u);
  EXPECT_EQ(t.degenerate_faces, 0u);
  // Every vertex is still on the base plane or the standing sheet's plane.
  for (const Vec3& v : m.vertices) {
    EXPECT_TRUE(v.z == 0 || v.x == 3) << v.x << " " << v.y << " " << v.z;
  }
}

TEST(DecimateTest, ThreeSheetsMeetingAtAPointKeepThePoint) {
  // The planar junction of the benchmark in miniature: planes z = 0 and x = 0 crossing
  // along the y axis, and a half-plane y = 0 (x, z >= 0) ending against both.
  TriangleMesh m;
  auto add_grid = [&m](auto at) {
    const TriangleMesh g = Grid(8, 8, at);
    const uint32_t o = static_cast<uint32_t>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), g.vertices.begin(), g.vertices.end());
    for (const Face& f : g.faces) m.faces.push_back({f[0] + o, f[1] + o, f[2] + o});
  };
  add_grid([](int i, int j) { return Vec3{i - 4.0, j - 4.0, 0}; });
  add_grid([](int i, int j) { return Vec3{0, j - 4.0, i - 4.0}; });
  add_grid([](int i, int j) { return Vec3{i * 0.5, 0, j * 0.5}; });
  // Weld coincident vertices so the sheets share their junction edges.
  std::vector<Vec3> unique;
  std::vector<uint32_t> index;
  for (const Vec3& v : m.vertices) {
    auto it = std::find(unique.begin(), unique.end(), v);
    index.push_back(static_cast<uint32_t>(it - unique.begin()));
    if (it == unique.end()) unique.push_back(v);
  }
  for (Face& f : m.faces)
    for (uint32_t& v : f) v = index[v];
  m.vertices = unique;
  const double area = TotalArea(m);
  ASSERT_EQ(m.num_faces(), 384u);
  Decimate(&m, {.triangles = 1, .max_error = 1e-9});
  EXPECT_LE(m.num_faces(), 50u);  // 66 with the junction held fixed
  EXPECT_NEAR(TotalArea(m), area, 1e-6);
  EXPECT_TRUE(std::find(m.vertices.begin(), m.vertices.end(), Vec3{0, 0, 0}) != m.vertices.end())
      << "the point where the three sheets meet moved";
  EXPECT_EQ(AnalyzeTopology(m).duplicate_faces, 0u);
}

}  // namespace
}  // namespace sheetmesh
