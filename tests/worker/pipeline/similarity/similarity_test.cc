#include "worker/pipeline/similarity/similarity.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "tests/testing/shapes.h"
#include "tests/testing/status_matchers.h"
#include "worker/pipeline/similarity/mesh_model.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::BoxSet;
using ::sheetmesh::testing::StatusIs;

// One right triangle with legs 10 in the plane z = 5.
TriangleMesh RightTriangle(float thickness) {
  TriangleMesh m;
  m.vertices = {{0, 0, 5}, {10, 0, 5}, {0, 10, 5}};
  m.faces = {{0, 1, 2}};
  m.face_thickness_voxels = {thickness};
  return m;
}

TEST(MeshModelTest, PrismOfARightTriangleHasTheExactVoxels) {
  const Dims d{16, 16, 12};
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet prism, VoxelizePrisms(RightTriangle(3), d));
  // Points with x, y >= 0 and x + y <= 10: 66 per layer; |z - 5| <= 1.5: z in {4, 5, 6}.
  EXPECT_EQ(prism.size(), 3u * 66);
  EXPECT_TRUE(prism.Contains(10, 0, 6));
  EXPECT_TRUE(prism.Contains(0, 10, 4));
  EXPECT_FALSE(prism.Contains(6, 5, 5));
  EXPECT_FALSE(prism.Contains(0, 0, 7));
}

TEST(MeshModelTest, ZeroThicknessAddsNothingAndTheShellFollowsVertexThickness) {
  const Dims d{16, 16, 12};
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet none, VoxelizePrisms(RightTriangle(0), d));
  EXPECT_TRUE(none.empty());
  TriangleMesh m = RightTriangle(0);
  m.vertex_thickness_voxels = {5, 1, 1};  // thick at the origin, thin at the far corners
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet shell, VoxelizePrisms(m, d, PrismHeight::kVertex));
  EXPECT_TRUE(shell.Contains(0, 0, 7));    // half thickness 2.5 at the origin
  EXPECT_FALSE(shell.Contains(10, 0, 6));  // half thickness 0.5 at (10, 0)
  EXPECT_TRUE(shell.Contains(10, 0, 5));
  TriangleMesh bad = RightTriangle(1);
  EXPECT_THAT(VoxelizePrisms(bad, d, PrismHeight::kVertex),
              StatusIs(absl::StatusCode::kInvalidArgument));
  bad.face_thickness_voxels.clear();
  EXPECT_THAT(VoxelizePrisms(bad, d), StatusIs(absl::StatusCode::kInvalidArgument));
}

TEST(SimilarityTest, Formula5OnHandMadeSets) {
  const Dims d{16, 16, 12};
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet prism, VoxelizePrisms(RightTriangle(3), d));
  // The exact model scores 1.
  SimilarityScore s = ScoreModel(prism, prism);
  EXPECT_EQ(s.c_in, 198u);
  EXPECT_EQ(s.c_out, 0u);
  EXPECT_DOUBLE_EQ(s.similarity, 1.0);
  EXPECT_DOUBLE_EQ(s.dice, 1.0);
  // Against only the middle layer: 66 in, 132 out: (66 - 132) / 66 = -1.
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet layer, VoxelizePrisms(RightTriangle(1), d));
  ASSERT_EQ(layer.size(), 66u);
  s = ScoreModel(prism, layer);
  EXPECT_EQ(s.c_in, 66u);
  EXPECT_EQ(s.c_out, 132u);
  EXPECT_DOUBLE_EQ(s.similarity, -1.0);
  EXPECT_DOUBLE_EQ(s.dice, 2.0 * 66 / (198 + 66));
  // The layer as model of the prism: 66 in, 0 out, a third of the image.
  s = ScoreModel(layer, prism);
  EXPECT_DOUBLE_EQ(s.similarity, 66.0 / 198.0);
}

TEST(SimilarityTest, HausdorffDistanceOfKnownSets) {
  const Dims d{10, 10, 10};
  const VoxelSet a = VoxelSet::FromIndices(d, {{0, 0, 0}});
  const VoxelSet b = VoxelSet::FromIndices(d, {{3, 4, 0}});
  SM_ASSERT_OK_AND_ASSIGN(double h, HausdorffDistance(a, b));
  EXPECT_DOUBLE_EQ(h, 5.0);
  const VoxelSet box = BoxSet(d, {0, 0, 0}, {4, 4, 4});
  const VoxelSet bigger = BoxSet(d, {0, 0, 0}, {4, 4, 7});
  SM_ASSERT_OK_AND_ASSIGN(h, HausdorffDistance(box, bigger));
  EXPECT_DOUBLE_EQ(h, 3.0);
  SM_ASSERT_OK_AND_ASSIGN(h, HausdorffDistance(box, box));
  EXPECT_DOUBLE_EQ(h, 0.0);
  SM_ASSERT_OK_AND_ASSIGN(h, HausdorffDistance(box, VoxelSet(d)));
  EXPECT_TRUE(std::isinf(h));
}

TEST(SimilarityTest, ClosedSurfaceOfACubeEnclosesItsVoxels) {
  // The cube [0.5, 10.5]^3 encloses voxel centres 1..10 on each axis.
  TriangleMesh cube;
  for (int i = 0; i < 8; ++i) {
    cube.vertices.push_back({i & 1 ? 10.5 : 0.5, i & 2 ? 10.5 : 0.5, i & 4 ? 10.5 : 0.5});
  }
  cube.faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet inside, VoxelizeClosedSurface(cube, {16, 16, 16}));
  EXPECT_EQ(inside.size(), 1000u);
  EXPECT_EQ(inside, BoxSet({16, 16, 16}, {1, 1, 1}, {11, 11, 11}));
}

TEST(SimilarityTest, GridModelsFollowTable2) {
  const Dims d{64, 64, 16};
  const VoxelSet slab = testing::PlaneSlab(d, {32, 32, 8}, {0, 0, 1}, 5);
  EXPECT_EQ(GridModel(slab, 1), slab);
  double last = 1.0;
  for (int k : {2, 3, 4}) {
    const double s = ScoreModel(GridModel(slab, k), slab).similarity;
    EXPECT_LT(s, last) << "similarity falls as the sampling rate grows";
    last = s;
  }
  // A full box samples exactly back to itself for k dividing its size.
  const VoxelSet box = BoxSet({8, 8, 8}, {0, 0, 0}, {8, 8, 8});
  EXPECT_EQ(GridModel(box, 2), box);
  EXPECT_EQ(GridModel(box, 4), box);
  EXPECT_EQ(GridQuantity({1012, 1024, 931}, 2), 506ull * 512 * 466);
  EXPECT_EQ(GridQuantity({1012, 1024, 931}, 1), 1012ull * 1024 * 931);
}

}  // namespace
}  // namespace sheetmesh
