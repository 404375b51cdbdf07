#include "worker/pipeline/surface/vertex_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "tests/testing/shapes.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/similarity/mesh_model.h"
#include "worker/pipeline/similarity/similarity.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::BoxSet;

// A flat grid of n × n squares, two triangles each, over [x0, x1] × [y0, y1] at height z,
// every face `thickness` high.
TriangleMesh FlatGrid(double x0, double x1, double y0, double y1, double z, int n,
                      float thickness) {
  TriangleMesh m;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      m.vertices.push_back({x0 + (x1 - x0) * i / n, y0 + (y1 - y0) * j / n, z});
    }
  }
  auto at = [&](int i, int j) { return static_cast<uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      m.faces.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.faces.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  m.face_thickness_voxels.assign(m.faces.size(), thickness);
  m.face_piece.assign(m.faces.size(), 0);
  return m;
}

double Similarity(const TriangleMesh& mesh, const VoxelSet& set) {
  auto model = VoxelizePrisms(mesh, set.dims());
  EXPECT_TRUE(model.ok()) << model.status();
  return ScoreModel(*model, set).similarity;
}

// A slab 4 voxels thick (z = 10..13, mid-plane 11.5) over x, y = 8..39.
VoxelSet Slab() { return BoxSet({48, 48, 24}, {8, 8, 10}, {40, 40, 14}); }

TEST(FitVertexPositionsTest, AMidSurfaceOffTheMiddleMovesBackOntoIt) {
  const VoxelSet set = Slab();
  // One voxel above the middle, the outline on the outermost voxels' centres.
  TriangleMesh mesh = FlatGrid(8, 39, 8, 39, 12.5, 4, 4.0f);
  const double before = Similarity(mesh, set);
  EXPECT_LT(before, 0.6);
  VertexFitOptions o;
  EXPECT_EQ(FitVertexPositions(&mesh, set, o).moves, 0u) << "only rims move by default";
  o.along_normal = true;
  const VertexFitStats stats = FitVertexPositions(&mesh, set, o);
  EXPECT_GE(stats.moves, mesh.vertices.size()) << "every vertex was one voxel off";
  for (const Vec3& v : mesh.vertices) EXPECT_DOUBLE_EQ(v.z, 11.5);
  EXPECT_DOUBLE_EQ(Similarity(mesh, set), 1.0);
  // The gain reported is the rise of formula 5's numerator.
  EXPECT_NEAR(double(stats.voxels_gained) / set.size(), 1.0 - before, 1e-12);
}

TEST(FitVertexPositionsTest, ARimShortOfTheOutlineMovesOut) {
  const VoxelSet set = Slab();
  // On the mid-plane, the outline a voxel inside the slab's on every side.
  TriangleMesh mesh = FlatGrid(9, 38, 9, 38, 11.5, 4, 4.0f);
  const double before = Similarity(mesh, set);
  const VertexFitStats stats = FitVertexPositions(&mesh, set);
  EXPECT_GT(stats.moves, 0u);
  const double after = Similarity(mesh, set);
  EXPECT_GT(after, before + 0.08);
  EXPECT_GE(after, 0.98);
  for (const Vec3& v : mesh.vertices) {
    // At most to the outermost voxels' outer faces, and within half a voxel of the middle.
    EXPECT_NEAR(v.z, 11.5, 0.5 + 1e-9);
    EXPECT_GE(v.x, 7.5 - 1e-9);
    EXPECT_LE(v.x, 39.5 + 1e-9);
  }
}

TEST(FitVertexPositionsTest, VerticesOnAndBesideAJunctionAndCoordinatesInTheBoxFacesStay) {
  // The slab reaches the box's faces x = -0.5 and x = 47.5, and so does the mesh.
  const VoxelSet set = BoxSet({48, 48, 24}, {0, 8, 10}, {48, 40, 14});
  TriangleMesh mesh = FlatGrid(-0.5, 47.5, 8, 39, 12.5, 4, 4.0f);
  // A fin standing on the grid's middle row (y = 23.5) makes that row a junction.
  const uint32_t base = static_cast<uint32_t>(mesh.vertices.size());
  for (int i = 0; i <= 4; ++i) mesh.vertices.push_back({-0.5 + 48.0 * i / 4, 23.5, 20.0});
  for (int i = 0; i < 4; ++i) {
    const uint32_t a = static_cast<uint32_t>(2 * 5 + i), b = a + 1;  // row j = 2
    mesh.faces.push_back({a, b, base + i + 1});
    mesh.faces.push_back({a, base + i + 1, base + i});
    mesh.face_thickness_voxels.push_back(4.0f);
    mesh.face_thickness_voxels.push_back(4.0f);
    mesh.face_piece.push_back(0);
    mesh.face_piece.push_back(0);
  }
  const std::vector<Vec3> start = mesh.vertices;
  VertexFitOptions o;
  o.along_normal = true;
  FitVertexPositions(&mesh, set, o);
  for (uint32_t v = 0; v < 25; ++v) {
    const uint32_t row = v / 5;
    if (row >= 1 && row <= 3) {
      EXPECT_EQ(mesh.vertices[v], start[v]) << "vertex " << v << " on or beside the junction";
    } else {
      EXPECT_NEAR(mesh.vertices[v].z, 11.5, 0.5) << "vertex " << v;
    }
    if (start[v].x == -0.5 || start[v].x == 47.5) {
      EXPECT_EQ(mesh.vertices[v].x, start[v].x) << "vertex " << v << " left the box's face";
    }
  }
}

TEST(FitVertexPositionsTest, ARimNearAFaceOfTheBoxGoesOntoIt) {
  // The slab reaches the box's faces x = 0 and x = 47; the mesh stops a voxel short of both.
  const VoxelSet set = BoxSet({48, 48, 24}, {0, 8, 10}, {48, 40, 14});
  TriangleMesh mesh = FlatGrid(1, 46, 8, 39, 11.5, 4, 4.0f);
  const double before = Similarity(mesh, set);
  FitVertexPositions(&mesh, set);
  for (uint32_t v = 0; v < mesh.vertices.size(); ++v) {
    // The box's faces: the outer faces of the outermost voxels.
    if (v % 5 == 0) EXPECT_EQ(mesh.vertices[v].x, -0.5) << "vertex " << v;
    if (v % 5 == 4) EXPECT_EQ(mesh.vertices[v].x, 47.5) << "vertex " << v;
  }
  EXPECT_GT(Similarity(mesh, set), before);
}

TEST(FitVertexPositionsTest, NoFaceTurnsOrSharpensPastTheBounds) {
  // A stepped sheet: its second half 3 voxels higher, a move no vertex can make whole
  // within the bounds.
  const VoxelSet set = testing::ShapeSet({48, 48, 24}, [](double x, double y, double z) {
    const double bottom = x < 24 ? 10 : 13;
    return x >= 8 && x < 40 && y >= 8 && y < 40 && z >= bottom && z < bottom + 4;
  });
  TriangleMesh mesh = FlatGrid(8, 39, 8, 39, 11.5, 8, 4.0f);
  std::vector<Vec3> normal_before;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    normal_before.push_back(UnitNormal(Corners(mesh, f)));
  }
  const double before = Similarity(mesh, set);
  VertexFitOptions o;
  o.along_normal = true;
  FitVertexPositions(&mesh, set, o);
  EXPECT_GT(Similarity(mesh, set), before);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Triangle t = Corners(mesh, f);
    EXPECT_GE(Dot(UnitNormal(t), normal_before[f]),
              std::cos(o.max_normal_turn * M_PI / 180) - 1e-12)
        << "face " << f;
    EXPECT_GE(MinAngleDegrees(t), o.min_angle - 1e-9) << "face " << f;
  }
}

}  // namespace
}  // namespace sheetmesh
