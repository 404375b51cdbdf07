#include "worker/pipeline/extract/extend.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/testing/shapes.h"
#include "tests/testing/status_matchers.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::BoxSet;
using ::sheetmesh::testing::StatusIs;

LabelledVoxels Labelled(const VoxelSet& set) {
  return LabelByComponents(set, *LabelComponents(set, Connectivity::k6));
}

uint32_t ComponentsAfterDetection(const VoxelSet& set) {
  auto r = Extend(Labelled(set), ExtendOptions{});
  EXPECT_TRUE(r.ok()) << r.status();
  return LabelComponents(r->patch.set, Connectivity::k6)->count();
}

TEST(ExtendTest, CoplanarFragmentsCloserThanRMerge) {
  const Dims d{72, 48, 24};
  const VoxelSet a = BoxSet(d, {4, 8, 10}, {32, 40, 15});
  const VoxelSet near = BoxSet(d, {36, 8, 10}, {66, 40, 15});  // gap of 4 < R = 7
  EXPECT_EQ(ComponentsAfterDetection(Union(a, near)), 1u);
}

TEST(ExtendTest, FragmentsFartherThanROrInOtherPlanesStaySeparate) {
  const Dims d{72, 48, 40};
  const VoxelSet a = BoxSet(d, {4, 8, 10}, {28, 40, 15});
  const VoxelSet far = BoxSet(d, {44, 8, 10}, {68, 40, 15});  // gap of 16 > R
  EXPECT_EQ(ComponentsAfterDetection(Union(a, far)), 2u);
  const VoxelSet other_plane = BoxSet(d, {32, 8, 24}, {60, 40, 29});  // close but 14 above
  EXPECT_EQ(ComponentsAfterDetection(Union(a, other_plane)), 2u);
}

TEST(ExtendTest, RecoveryAddsOnlyOriginalVoxelsAndClosesAGap) {
  // A sheet 2t = 3 thick, as formula 4 assumes.
  const Dims d{72, 48, 24};
  const VoxelSet original = BoxSet(d, {4, 8, 10}, {66, 40, 13});
  // A gap cut out of the original, as separation does.
  const VoxelSet cut = Difference(original, BoxSet(d, {33, 0, 0}, {37, 48, 24}));
  ExtendOptions o;
  o.max_rounds = 10;
  SM_ASSERT_OK_AND_ASSIGN(ExtendResult r, Extend(Labelled(cut), o, &original));
  EXPECT_TRUE(Difference(r.patch.set, original).empty()) << "only voxels of the original";
  EXPECT_EQ(r.patch.set, original) << "the gap is closed";
  EXPECT_GT(r.added, 0u);
  // Each half keeps its own label; the gap is shared between them.
  EXPECT_EQ(r.patch.CountLabels(), 2u);
}

TEST(ExtendTest, ACylinderThinnerThanTheSheetRecoversOnlyItsMiddle) {
  const Dims d{72, 48, 24};
  const VoxelSet original = BoxSet(d, {4, 8, 10}, {66, 40, 15});  // 5 thick
  const VoxelSet cut = Difference(original, BoxSet(d, {33, 0, 0}, {37, 48, 24}));
  ExtendOptions o;
  o.max_rounds = 10;
  SM_ASSERT_OK_AND_ASSIGN(ExtendResult thin, Extend(Labelled(cut), o, &original));
  EXPECT_FALSE(thin.patch.set.Contains(35, 20, 10))
      << "t = 1.5 reaches one voxel off the mid-plane";
  EXPECT_TRUE(thin.patch.set.Contains(35, 20, 12));
  o.half_thickness_voxels = 2.6;  // 2t covers the thickness
  SM_ASSERT_OK_AND_ASSIGN(ExtendResult thick, Extend(Labelled(cut), o, &original));
  EXPECT_EQ(thick.patch.set, original);
}

TEST(ExtendTest, BadParametersAreInvalidArgument) {
  ExtendOptions o;
  o.radius_voxels = 0;
  EXPECT_THAT(Extend(Labelled(BoxSet({8, 8, 8}, {1, 1, 1}, {7, 7, 3})), o),
              StatusIs(absl::StatusCode::kInvalidArgument));
}

}  // namespace
}  // namespace sheetmesh
