#include "worker/pipeline/voxel/thickness.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "tests/testing/status_matchers.h"

namespace sheetmesh {
namespace {

// A box [lo, hi) of voxels.
VoxelSet Box(const Dims& d, Index3 lo, Index3 hi) {
  VoxelSet::Builder b(d);
  for (int z = lo.z; z < hi.z; ++z) {
    for (int y = lo.y; y < hi.y; ++y) b.AddRun(y, z, lo.x, hi.x);
  }
  return std::move(b).Build();
}

class SlabThicknessTest : public ::testing::TestWithParam<std::tuple<int, int>> {};

TEST_P(SlabThicknessTest, SlabThicknessIsItsWidthAlongTheThinAxis) {
  const auto [axis, width] = GetParam();
  const Dims d{40, 40, 40};
  Index3 lo{2, 3, 4}, hi{38, 37, 36};
  if (axis == 0) hi.x = lo.x + width;
  if (axis == 1) hi.y = lo.y + width;
  if (axis == 2) hi.z = lo.z + width;
  const VoxelSet slab = Box(d, lo, hi);
  SM_ASSERT_OK_AND_ASSIGN(std::vector<uint16_t> tau, ComputeThickness(slab));
  for (uint16_t t : tau) ASSERT_EQ(t, width);
  const ThicknessStats s = SummarizeThickness(tau);
  EXPECT_DOUBLE_EQ(s.mean, width);
  EXPECT_EQ(s.min, static_cast<uint32_t>(width));
  EXPECT_EQ(s.max, static_cast<uint32_t>(width));
  EXPECT_EQ(s.histogram[width], tau.size());
}

INSTANTIATE_TEST_SUITE_P(AllAxes, SlabThicknessTest,
                         ::testing::Combine(::testing::Values(0, 1, 2),
                                            ::testing::Values(1, 3, 5, 8)));

TEST(ThicknessTest, MatchesBruteForceOnRandomSets) {
  const Dims d{13, 11, 9};
  std::mt19937 rng(5);
  std::vector<Index3> idx;
  for (int i = 0; i < 600; ++i) {
    idx.push_back({int(rng() % d.nx), int(rng() % d.ny), int(rng() % d.nz)});
  }
  const VoxelSet s = VoxelSet::FromIndices(d, idx);
  SM_ASSERT_OK_AND_ASSIGN(std::vector<uint16_t> tau, ComputeThickness(s));
  s.ForEachVoxel([&](uint64_t i, int32_t x, int32_t y, int32_t z) {
    int best = 1 << 30;
    const int step[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (const auto& st : step) {
      int run = 1;
      for (int k = 1; s.Contains(x + k * st[0], y + k * st[1], z + k * st[2]); ++k) ++run;
      for (int k = 1; s.Contains(x - k * st[0], y - k * st[1], z - k * st[2]); ++k) ++run;
      best = std::min(best, run);
    }
    ASSERT_EQ(tau[i], best) << "voxel " << x << "," << y << "," << z;
  });
}

TEST(ThicknessTest, EmptySetHasZeroStatistics) {
  VoxelSet s(Dims{4, 4, 4});
  SM_ASSERT_OK_AND_ASSIGN(std::vector<uint16_t> tau, ComputeThickness(s));
  EXPECT_TRUE(tau.empty());
  EXPECT_EQ(SummarizeThickness(tau).mean, 0);
}

TEST(ThicknessTest, MedianOfMixedThickness) {
  const std::vector<uint16_t> t = {1, 2, 2, 3, 9};
  const ThicknessStats s = SummarizeThickness(t);
  EXPECT_EQ(s.median, 2);
  EXPECT_DOUBLE_EQ(s.mean, 17.0 / 5);
  EXPECT_EQ(s.max, 9u);
}

}  // namespace
}  // namespace sheetmesh
