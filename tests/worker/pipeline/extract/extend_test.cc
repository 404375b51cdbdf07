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

// The dense store, one list, and a list gathered in many thin slabs give the same patch.
TEST(ExtendTest, TheDenseAndTheListedClaimsGiveTheSamePatch) {
  // Two crossing slabs and a fragment, so that cylinders compete for voxels.
  const Dims d{64, 56, 40};
  const VoxelSet set =
      Union(Union(BoxSet(d, {4, 6, 18}, {40, 50, 21}), BoxSet(d, {30, 6, 4}, {33, 50, 36})),
            BoxSet(d, {46, 10, 18}, {60, 44, 21}));
  for (const double t : {1.5, 4.0}) {
    ExtendOptions list, dense;
    list.half_thickness_voxels = dense.half_thickness_voxels = t;
    list.max_rounds = dense.max_rounds = 2;
    list.claims = ExtendOptions::ClaimStore::kList;
    dense.claims = ExtendOptions::ClaimStore::kDense;
    ExtendOptions slabs = list;
    slabs.slab_claims = 500;  // a slab of a slice or two: dozens of slabs, cut through cylinders
    SM_ASSERT_OK_AND_ASSIGN(ExtendResult a, Extend(Labelled(set), list));
    SM_ASSERT_OK_AND_ASSIGN(ExtendResult b, Extend(Labelled(set), dense));
    SM_ASSERT_OK_AND_ASSIGN(ExtendResult c, Extend(Labelled(set), slabs));
    EXPECT_GT(a.added, 0u);
    EXPECT_EQ(a.added, b.added) << "t " << t;
    EXPECT_EQ(a.patch.set, b.patch.set) << "t " << t;
    EXPECT_EQ(a.patch.label, b.patch.label) << "t " << t;
    EXPECT_EQ(c.added, b.added) << "t " << t;
    EXPECT_EQ(c.patch.set, b.patch.set) << "t " << t;
    EXPECT_EQ(c.patch.label, b.patch.label) << "t " << t;
  }
}

TEST(ExtendTest, ARoundBeyondItsMemoryIsRefusedBeforeItStartsNamingTAndR) {
  const Dims d{64, 56, 40};
  const VoxelSet set = BoxSet(d, {4, 6, 18}, {40, 50, 21});
  ExtendOptions o;
  o.half_thickness_voxels = 30;
  o.radius_voxels = 500;
  o.memory_bytes = 1 << 16;  // less than one claim per voxel of the image
  EXPECT_THAT(
      Extend(Labelled(set), o),
      StatusIs(absl::StatusCode::kResourceExhausted,
               ::testing::AllOf(::testing::HasSubstr("t = 30"), ::testing::HasSubstr("R = 500"))));
  o.memory_bytes = int64_t{1} << 30;  // the whole image as dense claims fits
  SM_ASSERT_OK_AND_ASSIGN(ExtendResult r, Extend(Labelled(set), o));
  EXPECT_GT(r.added, 0u);
}

}  // namespace
}  // namespace sheetmesh
