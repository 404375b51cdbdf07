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

// A 9 x 9 grid of unit squares, two triangles each, placed by `at(i, j)`, i, j in [-4, 4].
template <class At>
std::pair<std::vector<Vec3>, std::vector<Face>> Grid(At at) {
  std::vector<Vec3> pos;
  std::vector<Face> faces;
  auto id = [](int i, int j) { return static_cast<uint32_t>((i + 4) * 9 + (j + 4)); };
  for (int i = -4; i <= 4; ++i)
    for (int j = -4; j <= 4; ++j) pos.push_back(at(i, j));
  for (int i = -4; i < 4; ++i) {
    for (int j = -4; j < 4; ++j) {
      faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  }
  return {pos, faces};
}

TEST(SeparationTest, ARoughPlaneIsFlatAtTheScaleOfItsRingsButAFoldIsNot) {
  // Heights alternating by ±0.2 fold neighbouring triangles by about 40°: the paper's test
  // cuts nearly every vertex; the two-ring fit sees one plane (tan 15° allows 0.27).
  auto [rough, rough_faces] = Grid([](int i, int j) {
    return Vec3{double(i), double(j), (i + j) % 2 == 0 ? 0.2 : -0.2};
  });
  const std::vector<uint8_t> paper = FlatVertices(rough, rough_faces, 150);
  EXPECT_GT(std::count(paper.begin(), paper.end(), 0), 60);
  // (Within two edges of the grid's rim a neighbourhood is too lopsided to tell.)
  const std::vector<uint8_t> fitted = FlatVertices(rough, rough_faces, 150, 2);
  for (int i = -2; i <= 2; ++i)
    for (int j = -2; j <= 2; ++j) EXPECT_EQ(fitted[(i + 4) * 9 + (j + 4)], 1) << i << ", " << j;
  // A right-angle fold along i = 0 is a fold at every scale.
  auto [folded, folded_faces] = Grid([](int i, int j) {
    return i <= 0 ? Vec3{double(i), double(j), 0} : Vec3{0, double(j), double(i)};
  });
  const std::vector<uint8_t> flat = FlatVertices(folded, folded_faces, 150, 2);
  for (int j = -4; j <= 4; ++j) EXPECT_EQ(flat[(0 + 4) * 9 + (j + 4)], 0) << "j = " << j;
  EXPECT_EQ(flat[0], 1);  // far from the fold
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
