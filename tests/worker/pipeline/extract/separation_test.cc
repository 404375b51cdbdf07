#include "worker/pipeline/extract/separation.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/testing/shapes.h"
#include "tests/testing/status_matchers.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::BoxSet;
using ::sheetmesh::testing::StatusIs;

TEST(SeparationTest, FlatnessFollowsAlgorithm2) {
  // Two triangles on edge (0, 1): flat continuation, a right angle, and a crossing edge.
  const std::vector<Vec3> flat_pos = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
  const std::vector<Face> two = {{0, 1, 2}, {0, 1, 3}};
  EXPECT_THAT(FlatVertices(flat_pos, two, 150), ::testing::Each(1));
  const std::vector<Vec3> bent_pos = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  EXPECT_THAT(FlatVertices(bent_pos, two, 150), ::testing::ElementsAre(0, 0, 1, 1));
  EXPECT_THAT(FlatVertices(bent_pos, two, 80), ::testing::Each(1));
  const std::vector<Vec3> cross_pos = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  const std::vector<Face> three = {{0, 1, 2}, {0, 1, 3}, {0, 1, 4}};
  EXPECT_THAT(FlatVertices(cross_pos, three, 10), ::testing::ElementsAre(0, 0, 1, 1, 1));
}

TEST(SeparationTest, PiercedPlateGivesThreePiecesAsFig4) {
  const Dims d{64, 64, 64};
  const VoxelSet plate = BoxSet(d, {5, 5, 30}, {59, 59, 35});
  const VoxelSet pierce = BoxSet(d, {30, 20, 5}, {35, 44, 59});
  SM_ASSERT_OK_AND_ASSIGN(SeparationResult r, Separate(Union(plate, pierce), {}));
  // Pieces above M-like noise: count those with a real share of the voxels.
  std::map<int32_t, uint64_t> size;
  for (int32_t l : r.pieces.label) ++size[l];
  int big = 0;
  for (const auto& [l, n] : size) big += n > 500;
  EXPECT_EQ(big, 3);
  EXPECT_GT(r.removed_voxels, 0u);
  EXPECT_GT(r.nonflat_generators, 0u);
  // The crossing is gone: no voxel where both plates overlap survives.
  EXPECT_TRUE(Intersection(r.pieces.set, Intersection(plate, pierce)).empty());
}

TEST(SeparationTest, FlatSlabStaysOnePiece) {
  SM_ASSERT_OK_AND_ASSIGN(
      SeparationResult r,
      Separate(testing::PlaneSlab({64, 64, 16}, {32, 32, 8}, {0, 0, 1}, 5), {}));
  EXPECT_EQ(r.pieces.CountLabels(), 1u);
  EXPECT_EQ(r.removed_voxels, 0u);
}

TEST(SeparationTest, BadAngleIsInvalidArgument) {
  SeparationOptions o;
  o.dihedral_degrees = 0;
  EXPECT_THAT(Separate(BoxSet({8, 8, 8}, {1, 1, 1}, {7, 7, 3}), o),
              StatusIs(absl::StatusCode::kInvalidArgument, ::testing::HasSubstr("D_ang")));
}

}  // namespace
}  // namespace sheetmesh
