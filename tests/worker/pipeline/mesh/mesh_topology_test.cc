#include "worker/pipeline/mesh/mesh_topology.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {
namespace {

// A grid of n x n quads in the plane z = 0, two triangles each; `skip` leaves a quad out.
TriangleMesh Grid(int n, int skip_x = -1, int skip_y = -1) {
  TriangleMesh m;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) m.vertices.push_back({double(x), double(y), 0});
  auto id = [n](int x, int y) { return static_cast<uint32_t>(y * (n + 1) + x); };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      if (x == skip_x && y == skip_y) continue;
      m.faces.push_back({id(x, y), id(x + 1, y), id(x + 1, y + 1)});
      m.faces.push_back({id(x, y), id(x + 1, y + 1), id(x, y + 1)});
    }
  return m;
}

TEST(MeshTopologyTest, GridWithAHoleHasTwoBoundaryLoops) {
  const TopologyReport plain = AnalyzeTopology(Grid(4));
  EXPECT_EQ(plain.boundary_loops, 1u);
  EXPECT_EQ(plain.nonmanifold_edges, 0u);
  EXPECT_EQ(plain.connected_parts, 1u);
  EXPECT_EQ(plain.inconsistent_edges, 0u);
  EXPECT_EQ(plain.edges, 4u * 5 * 2 + 16u);
  const TopologyReport holed = AnalyzeTopology(Grid(4, 1, 1));
  EXPECT_EQ(holed.boundary_loops, 2u);
}

TEST(MeshTopologyTest, DuplicateDegenerateAndNonManifoldFacesAreCounted) {
  TriangleMesh m = Grid(2);
  m.faces.push_back(m.faces[0]);  // duplicate: makes 3 faces on edges
  m.faces.push_back({m.faces[1][0], m.faces[1][0], m.faces[1][1]});  // degenerate
  const TopologyReport r = AnalyzeTopology(m);
  EXPECT_EQ(r.duplicate_faces, 1u);
  EXPECT_EQ(r.degenerate_faces, 1u);
  EXPECT_GT(r.nonmanifold_edges, 0u);
}

TEST(MeshTopologyTest, OrientConsistentlyFlipsTheOddFaces) {
  TriangleMesh m = Grid(3);
  for (size_t f = 0; f < m.faces.size(); f += 3) std::swap(m.faces[f][1], m.faces[f][2]);
  EXPECT_GT(AnalyzeTopology(m).inconsistent_edges, 0u);
  EXPECT_EQ(OrientConsistently(&m), 0u);
  EXPECT_EQ(AnalyzeTopology(m).inconsistent_edges, 0u);
}

TEST(MeshTopologyTest, MoebiusBandCannotBeOriented) {
  // A strip of 6 quads whose ends join with a half twist.
  TriangleMesh m;
  const int n = 6;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    const double t = a / 2;
    for (int s : {-1, 1}) {
      const double r = 3 + s * std::cos(t);
      m.vertices.push_back({r * std::cos(a), r * std::sin(a), s * std::sin(t)});
    }
  }
  for (int i = 0; i < n; ++i) {
    const uint32_t a0 = 2 * i, a1 = 2 * i + 1;
    uint32_t b0 = 2 * ((i + 1) % n), b1 = 2 * ((i + 1) % n) + 1;
    if (i == n - 1) std::swap(b0, b1);  // the twist
    m.faces.push_back({a0, b0, a1});
    m.faces.push_back({a1, b0, b1});
  }
  EXPECT_EQ(OrientConsistently(&m), 1u);
}

TEST(MeshTopologyTest, SelfIntersectionsAreFound) {
  TriangleMesh m;
  m.vertices = {{0, 0, 0},  {4, 0, 0},  {0, 4, 0},    // flat triangle
                {1, 1, -1}, {1, 1, 1},  {3, 3, 1},    // pierces it, no shared vertex
                {10, 0, 0}, {14, 0, 0}, {10, 4, 0}};  // far away
  m.faces = {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}};
  EXPECT_THAT(FindSelfIntersections(m), ::testing::ElementsAre(std::make_pair(0u, 1u)));
  // Two faces folded onto each other along a shared edge.
  TriangleMesh fold;
  fold.vertices = {{0, 0, 0}, {4, 0, 0}, {1, 3, 0}, {2, 2, 0.01}};
  fold.faces = {{0, 1, 2}, {0, 1, 3}};
  EXPECT_EQ(FindSelfIntersections(fold).size(), 1u);
  // A clean grid has none.
  EXPECT_THAT(FindSelfIntersections(Grid(5)), ::testing::IsEmpty());
}

TEST(TriangleGeometryTest, DihedralAnglesAreOrientationFree) {
  const Vec3 p(0, 0, 0), q(1, 0, 0);
  EXPECT_NEAR(DihedralAngleDegrees(p, q, {0, 1, 0}, {0, -1, 0}), 180.0, 1e-9);  // flat
  EXPECT_NEAR(DihedralAngleDegrees(p, q, {0, 1, 0}, {0, 0, 1}), 90.0, 1e-9);
  EXPECT_NEAR(DihedralAngleDegrees(p, q, {0, 1, 0}, {5, 2, 0}), 0.0, 1e-9);  // folded
  EXPECT_NEAR(DihedralAngleDegrees(q, p, {0, 0, 1}, {0, 1, 0}), 90.0, 1e-9);
}

TEST(TriangleGeometryTest, IntersectionAndDistance) {
  const Triangle a = {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0)};
  EXPECT_TRUE(TrianglesIntersect(a, {Vec3(1, 1, -1), Vec3(1, 1, 1), Vec3(2, 2, 1)}));
  EXPECT_FALSE(TrianglesIntersect(a, {Vec3(1, 1, 0.5), Vec3(2, 1, 1), Vec3(1, 2, 1)}));
  EXPECT_TRUE(
      TrianglesIntersect(a, {Vec3(1, 1, 0), Vec3(5, 1, 0), Vec3(1, 5, 0)}));  // coplanar overlap
  EXPECT_FALSE(
      TrianglesIntersect(a, {Vec3(5, 5, 0), Vec3(9, 5, 0), Vec3(5, 9, 0)}));  // coplanar apart
  EXPECT_DOUBLE_EQ(PointTriangleDistance2({1, 1, 3}, a), 9.0);
  EXPECT_DOUBLE_EQ(PointTriangleDistance2({-3, 0, 4}, a), 25.0);
  EXPECT_NEAR(MinAngleDegrees(a), 45.0, 1e-9);
}

TEST(MeshTopologyTest, WedgesSharingAVertexOverlapWhereTheirPlanesLineEntersBoth) {
  const Vec3 p(0, 0, 0);
  // T1 in z = 0 spanning 0..90 degrees; T2 stands on the diagonal (1, 1, 0), so their planes
  // meet along it, inside both: they share more than p.
  EXPECT_TRUE(WedgesOverlap(p, {4, 0, 0}, {0, 4, 0}, {3, 3, -2}, {3, 3, 2}));
  // T2 standing on the diagonal (-1, 1, 0): outside T1's angle.
  EXPECT_FALSE(WedgesOverlap(p, {4, 0, 0}, {0, 4, 0}, {-3, 3, -2}, {-3, 3, 2}));
  // T2 standing on T1's edge direction (1, 0, 0): a touch along the edge counts.
  EXPECT_TRUE(WedgesOverlap(p, {4, 0, 0}, {0, 4, 0}, {3, 0, -2}, {3, 0, 2}));
  // T2 above T1's plane only, leaning over it: the planes meet outside both angles.
  EXPECT_FALSE(WedgesOverlap(p, {4, 0, 0}, {0, 4, 0}, {-2, -1, 3}, {-1, -2, 3}));
  // In one plane: disjoint angles, then overlapping ones, then an identical one.
  EXPECT_FALSE(WedgesOverlap(p, {4, 0, 0}, {0, 4, 0}, {-4, 0, 0}, {0, -4, 0}));
  EXPECT_TRUE(WedgesOverlap(p, {4, 0, 0}, {0, 4, 0}, {3, 1, 0}, {-4, 1, 0}));
  EXPECT_TRUE(WedgesOverlap(p, {4, 0, 0}, {0, 4, 0}, {0, 5, 0}, {5, 0, 0}));
  // Neighbours in one plane (adjacent angles meeting along an edge) do not overlap.
  EXPECT_FALSE(WedgesOverlap(p, {4, 0, 0}, {0, 4, 0}, {0, 4, 0}, {-4, 0, 0}));
}

TEST(MeshTopologyTest, AFaceWithARepeatedCornerCountsItOnceAgainstAnother) {
  // (0, 0, 1) repeats corner 0; shared with (0, 2, 3) it is one corner, not two, and the
  // flat face (0, 0, 1) covers nothing beyond it. (Counted twice per occurrence, a face of
  // three equal corners overran the list of shared corners.)
  const std::vector<Vec3> v = {{0, 0, 0}, {4, 0, 0}, {0, 4, 0}, {0, 0, 4}};
  EXPECT_FALSE(FacesClash(v, {0, 0, 1}, {0, 2, 3}));
  EXPECT_FALSE(FacesClash(v, {0, 1, 1}, {0, 1, 1}));
}

}  // namespace
}  // namespace sheetmesh
