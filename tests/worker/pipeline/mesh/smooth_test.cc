// Thick-sheet smoothing: wander taken out where the sheet is thicker than the triangles are
// wide, thin sheets, rims and crossings left where they are.
#include "worker/pipeline/mesh/smooth.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/testing/meshes.h"

namespace sheetmesh {
namespace {

// An n x n grid of unit squares whose interior vertices wander in z by +-1 in a
// checkerboard.
TriangleMesh WanderingGrid(int n) {
  return testing::Grid(n, n, [n](int x, int y) {
    const bool inner = x > 0 && y > 0 && x < n && y < n;
    return Vec3(x, y, inner ? ((x + y) % 2 ? 1.0 : -1.0) : 0.0);
  });
}

double LargestWander(const TriangleMesh& m) {
  double w = 0;
  for (const Vec3& v : m.vertices) w = std::max(w, std::abs(v.z));
  return w;
}

TEST(SmoothTest, ThickSheetsLoseTheirWanderThinOnesKeepIt) {
  const TriangleMesh start = WanderingGrid(8);
  // Edges about 2 long (the wander included): thickness 4 gives weight 1, thickness 1 gives 0.
  for (const auto& [thickness, flattened] : {std::pair{4.0f, true}, std::pair{1.0f, false}}) {
    TriangleMesh m = start;
    const std::vector<float> tau(m.num_vertices(), thickness);
    const std::vector<double> w = ThicknessSmoothingWeights(m, tau);
    const size_t moved = SmoothVertices(&m, w);
    if (flattened) {
      EXPECT_EQ(moved, 7u * 7u) << "every interior vertex";
      EXPECT_LT(LargestWander(m), 0.2);
    } else {
      EXPECT_EQ(moved, 0u);
      EXPECT_EQ(m.vertices, start.vertices);
    }
  }
}

TEST(SmoothTest, RimAndCrossingVerticesStay) {
  TriangleMesh m = WanderingGrid(6);
  // A fin along the row y = 3 makes its edges non-manifold.
  const uint32_t top = static_cast<uint32_t>(m.vertices.size());
  m.vertices.push_back(Vec3(3, 3, 5));
  m.faces.push_back({3 * 7 + 2, 3 * 7 + 3, top});
  const TriangleMesh before = m;
  SmoothVertices(&m, std::vector<double>(m.num_vertices(), 1.0));
  for (uint32_t v = 0; v < m.num_vertices(); ++v) {
    const Vec3& p = before.vertices[v];
    const bool rim = p.x == 0 || p.y == 0 || p.x == 6 || p.y == 6 || v == top;
    const bool crossing = v == 3 * 7 + 2 || v == 3 * 7 + 3;
    if (rim || crossing) EXPECT_EQ(m.vertices[v], p) << "vertex " << v;
  }
}

}  // namespace
}  // namespace sheetmesh
