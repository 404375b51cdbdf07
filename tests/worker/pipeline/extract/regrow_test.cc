#include "worker/pipeline/extract/regrow.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/testing/shapes.h"
#include "tests/testing/status_matchers.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::BoxSet;
using ::sheetmesh::testing::StatusIs;

// Recovery's options: rounds 0, until nothing is added (ExtendOptions' default of 1 round
// is detection's).
ExtendOptions Recovery() {
  ExtendOptions o;
  o.max_rounds = 0;
  return o;
}

LabelledVoxels Labelled(const VoxelSet& set, int32_t label) {
  return LabelledVoxels{set, std::vector<int32_t>(set.size(), label)};
}

// A slab 20 voxels thick grows back whole from its left half: the planes' half-thickness
// follows the slab (formula 4's fixed t = 1.5 would give back a layer 3 voxels thick).
TEST(RegrowTest, AThickSlabGrowsBackWholeFromHalfOfIt) {
  const Dims d{64, 48, 40};
  const VoxelSet slab = BoxSet(d, {0, 0, 10}, {64, 48, 30});
  const VoxelSet half = BoxSet(d, {0, 0, 10}, {28, 48, 30});
  ExtendOptions o = Recovery();
  o.scvd_radius_voxels = 10;
  SM_ASSERT_OK_AND_ASSIGN(ExtendResult r, Regrow(Labelled(half, 3), o, slab));
  EXPECT_EQ(r.patch.set, slab);
  EXPECT_EQ(r.added, slab.size() - half.size());
  for (int32_t l : r.patch.label) ASSERT_EQ(l, 3);
  EXPECT_GE(r.rounds, 36) << "the front moves a voxel per round across the 36 missing";
}

TEST(RegrowTest, OnlyVoxelsOfTheImageAreAddedAndItStopsByItself) {
  const Dims d{64, 64, 24};
  const VoxelSet plate = BoxSet(d, {4, 4, 10}, {60, 60, 14});
  const VoxelSet patch = Difference(plate, BoxSet(d, {30, 0, 0}, {34, 64, 24}));   // a cut
  const VoxelSet image = Difference(plate, BoxSet(d, {30, 20, 0}, {34, 24, 24}));  // a hole
  const ExtendOptions o = Recovery();
  SM_ASSERT_OK_AND_ASSIGN(ExtendResult r, Regrow(Labelled(patch, 0), o, image));
  EXPECT_EQ(r.patch.set, image) << "the cut closes but for the image's own hole";
  ExtendOptions capped = o;
  capped.max_rounds = 1;
  SM_ASSERT_OK_AND_ASSIGN(ExtendResult one, Regrow(Labelled(patch, 0), capped, image));
  EXPECT_EQ(one.rounds, 1);
  EXPECT_LT(one.patch.set.size(), r.patch.set.size());
}

// Two plates crossing, the crossing cut out of both: each cut voxel goes back to the plate
// whose plane it lies nearer.
TEST(RegrowTest, AtACrossingEachVoxelGoesToTheNearerPlane) {
  const Dims d{64, 64, 64};
  const VoxelSet flat = BoxSet(d, {4, 4, 30}, {60, 60, 34});     // z in [30, 34)
  const VoxelSet upright = BoxSet(d, {30, 4, 4}, {34, 60, 60});  // x in [30, 34)
  const VoxelSet crossing = BoxSet(d, {26, 0, 26}, {38, 64, 38});
  LabelledVoxels patch;
  const VoxelSet a = Difference(flat, crossing), b = Difference(upright, crossing);
  patch.set = Union(a, b);
  patch.set.ForEachVoxel([&](uint64_t, int32_t x, int32_t y, int32_t z) {
    patch.label.push_back(a.Contains(x, y, z) ? 0 : 1);
  });
  const VoxelSet image = Union(flat, upright);
  SM_ASSERT_OK_AND_ASSIGN(ExtendResult r, Regrow(patch, Recovery(), image));
  EXPECT_EQ(r.patch.set, image);
  auto label_at = [&](int x, int y, int z) { return r.patch.label[r.patch.set.Find(x, y, z)]; };
  EXPECT_EQ(label_at(27, 30, 31), 0) << "in the flat plate, off the upright one";
  EXPECT_EQ(label_at(31, 30, 27), 1) << "in the upright plate, off the flat one";
}

TEST(RegrowTest, BadParametersAndOtherDimsAreInvalidArgument) {
  const Dims d{16, 16, 16};
  const VoxelSet s = BoxSet(d, {2, 2, 6}, {14, 14, 9});
  ExtendOptions o;
  o.half_thickness_voxels = 0;
  EXPECT_THAT(Regrow(Labelled(s, 0), o, s),
              StatusIs(absl::StatusCode::kInvalidArgument, ::testing::HasSubstr("t = 0")));
  EXPECT_THAT(Regrow(Labelled(s, 0), ExtendOptions{}, VoxelSet(Dims{8, 8, 8})),
              StatusIs(absl::StatusCode::kInvalidArgument, ::testing::HasSubstr("dims")));
}

}  // namespace
}  // namespace sheetmesh
