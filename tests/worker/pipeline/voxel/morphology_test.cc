#include "worker/pipeline/voxel/morphology.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "tests/testing/status_matchers.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::StatusIs;

int Neighbourhood(Connectivity c) {
  return c == Connectivity::k6 ? 1 : (c == Connectivity::k18 ? 2 : 3);
}

// Reference dilation/erosion by one step, voxel by voxel.
VoxelSet BruteStep(const VoxelSet& s, Connectivity c, bool dilate) {
  const Dims& d = s.dims();
  std::vector<Index3> out;
  for (int z = 0; z < d.nz; ++z) {
    for (int y = 0; y < d.ny; ++y) {
      for (int x = 0; x < d.nx; ++x) {
        bool any = false, all = true;
        for (int dz = -1; dz <= 1; ++dz) {
          for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
              if ((dx != 0) + (dy != 0) + (dz != 0) > Neighbourhood(c)) continue;
              const bool inside = d.Contains(x + dx, y + dy, z + dz);
              const bool set = inside && s.Contains(x + dx, y + dy, z + dz);
              any |= set;
              all &= set || !inside;
            }
          }
        }
        if (dilate ? any : (all && s.Contains(x, y, z))) out.push_back({x, y, z});
      }
    }
  }
  return VoxelSet::FromIndices(d, out);
}

TEST(MorphologyTest, DilatingOneVoxelGivesTheStructuringElement) {
  const Dims d{9, 9, 9};
  const VoxelSet one = VoxelSet::FromIndices(d, {{4, 4, 4}});
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet d6, Dilate(one, 1, Connectivity::k6));
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet d18, Dilate(one, 1, Connectivity::k18));
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet d26, Dilate(one, 1, Connectivity::k26));
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet d6r2, Dilate(one, 2, Connectivity::k6));
  EXPECT_EQ(d6.size(), 7u);
  EXPECT_EQ(d18.size(), 19u);
  EXPECT_EQ(d26.size(), 27u);
  EXPECT_EQ(d6r2.size(), 25u);  // the L1 ball of radius 2
}

TEST(MorphologyTest, StepsMatchBruteForceOnRandomSets) {
  const Dims d{11, 9, 7};
  std::mt19937 rng(3);
  std::vector<Index3> idx;
  for (int i = 0; i < 250; ++i) idx.push_back({int(rng() % 11), int(rng() % 9), int(rng() % 7)});
  const VoxelSet s = VoxelSet::FromIndices(d, idx);
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet dense, Dilate(s, 1, Connectivity::k6));
  for (Connectivity c : {Connectivity::k6, Connectivity::k18, Connectivity::k26}) {
    SM_ASSERT_OK_AND_ASSIGN(VoxelSet dl, Dilate(s, 1, c));
    EXPECT_EQ(dl, BruteStep(s, c, true)) << static_cast<int>(c);
    SM_ASSERT_OK_AND_ASSIGN(VoxelSet er, Erode(dense, 1, c));
    EXPECT_EQ(er, BruteStep(dense, c, false)) << static_cast<int>(c);
  }
}

TEST(MorphologyTest, ClosingBridgesAOneVoxelGapAndOpeningRemovesSpecks) {
  const Dims d{30, 20, 20};
  VoxelSet::Builder b(d);
  for (int z = 8; z < 12; ++z) {
    for (int y = 2; y < 18; ++y) {
      b.AddRun(y, z, 2, 14);
      b.AddRun(y, z, 15, 28);  // gap at x = 14
    }
  }
  const VoxelSet slab = std::move(b).Build();
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet closed, Close(slab, 1));
  EXPECT_TRUE(closed.Contains(14, 10, 10));
  EXPECT_EQ(closed, BruteStep(BruteStep(slab, Connectivity::k6, true), Connectivity::k6, false));
  // The cross element cannot reach the gap's rim on the slab's faces; all inside fills.
  for (int z = 9; z <= 10; ++z)
    for (int y = 3; y <= 16; ++y) EXPECT_TRUE(closed.Contains(14, y, z)) << y << "," << z;

  const VoxelSet with_speck = Union(slab, VoxelSet::FromIndices(d, {{5, 5, 2}}));
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet opened, Open(with_speck, 1));
  EXPECT_FALSE(opened.Contains(5, 5, 2));
  EXPECT_TRUE(opened.Contains(6, 10, 10));
}

TEST(MorphologyTest, ErosionDoesNotEatAtTheBoxWall) {
  const Dims d{10, 10, 10};
  VoxelSet::Builder b(d);
  for (int z = 0; z < 10; ++z) {
    for (int y = 0; y < 10; ++y) b.AddRun(y, z, 0, 10);
  }
  const VoxelSet full = std::move(b).Build();
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet e, Erode(full, 2));
  EXPECT_EQ(e, full);
}

TEST(MorphologyTest, NegativeRadiusIsInvalidArgument) {
  VoxelSet s(Dims{3, 3, 3});
  EXPECT_THAT(Dilate(s, -1), StatusIs(absl::StatusCode::kInvalidArgument));
}

}  // namespace
}  // namespace sheetmesh
