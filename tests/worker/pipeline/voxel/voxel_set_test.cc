#include "worker/pipeline/voxel/voxel_set.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>
#include <tuple>
#include <vector>

namespace sheetmesh {
namespace {

using Key = std::tuple<int, int, int>;  // (z, y, x) for index order

std::set<Key> RandomKeys(const Dims& d, int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::set<Key> keys;
  for (int i = 0; i < n; ++i) {
    keys.insert({int(rng() % d.nz), int(rng() % d.ny), int(rng() % d.nx)});
  }
  return keys;
}

VoxelSet FromKeys(const Dims& d, const std::set<Key>& keys) {
  std::vector<Index3> idx;
  for (const auto& [z, y, x] : keys) idx.push_back({x, y, z});
  return VoxelSet::FromIndices(d, idx);
}

std::set<Key> ToKeys(const VoxelSet& s) {
  std::set<Key> keys;
  s.ForEachVoxel([&](uint64_t, int32_t x, int32_t y, int32_t z) { keys.insert({z, y, x}); });
  return keys;
}

TEST(VoxelSetTest, BuilderMergesTouchingRunsAndClipsToTheBox) {
  VoxelSet::Builder b(Dims{10, 2, 2});
  b.AddRun(0, 0, -3, 2);
  b.AddRun(0, 0, 2, 4);  // touches the previous run: merges
  b.AddRun(0, 0, 6, 7);
  b.AddRun(1, 1, 8, 20);
  VoxelSet s = std::move(b).Build();
  ASSERT_EQ(s.num_runs(), 3);
  EXPECT_EQ(s.size(), 4u + 1u + 2u);
  EXPECT_EQ(s.RowRuns(0, 0)[0], (::sheetmesh::Run{0, 4}));
  EXPECT_EQ(s.RowRuns(1, 1)[0], (::sheetmesh::Run{8, 10}));
  EXPECT_TRUE(s.RowRuns(1, 0).empty());
}

TEST(VoxelSetTest, FindAndCoordOfAgreeWithIndexOrder) {
  const Dims d{17, 9, 7};
  const std::set<Key> keys = RandomKeys(d, 300, 1);
  VoxelSet s = FromKeys(d, keys);
  ASSERT_EQ(s.size(), keys.size());
  uint64_t expected = 0;
  for (const auto& [z, y, x] : keys) {
    EXPECT_EQ(s.Find(x, y, z), static_cast<int64_t>(expected));
    const Index3 c = s.CoordOf(expected);
    EXPECT_EQ(c, (Index3{x, y, z}));
    ++expected;
  }
  EXPECT_EQ(s.Find(-1, 0, 0), -1);
  EXPECT_EQ(s.Find(0, 0, 99), -1);
}

TEST(VoxelSetTest, FindUsesBinarySearchOnLongRows) {
  VoxelSet::Builder b(Dims{100, 1, 1});
  for (int x = 0; x < 100; x += 3) b.AddVoxel(x, 0, 0);
  VoxelSet s = std::move(b).Build();
  EXPECT_EQ(s.Find(0, 0, 0), 0);
  EXPECT_EQ(s.Find(99, 0, 0), 33);
  EXPECT_EQ(s.Find(98, 0, 0), -1);
  EXPECT_EQ(s.Find(51, 0, 0), 17);
}

TEST(VoxelSetTest, SetAlgebraMatchesStdSet) {
  const Dims d{23, 11, 5};
  const std::set<Key> a = RandomKeys(d, 400, 2), b = RandomKeys(d, 400, 3);
  const VoxelSet sa = FromKeys(d, a), sb = FromKeys(d, b);
  std::set<Key> u, i, df;
  std::set_union(a.begin(), a.end(), b.begin(), b.end(), std::inserter(u, u.end()));
  std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::inserter(i, i.end()));
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::inserter(df, df.end()));
  EXPECT_EQ(ToKeys(Union(sa, sb)), u);
  EXPECT_EQ(ToKeys(Intersection(sa, sb)), i);
  EXPECT_EQ(ToKeys(Difference(sa, sb)), df);
}

TEST(VoxelSetTest, FilterKeepsFlaggedVoxels) {
  const Dims d{8, 8, 8};
  VoxelSet s = FromKeys(d, RandomKeys(d, 200, 4));
  std::vector<uint8_t> keep(s.size());
  std::set<Key> expected;
  s.ForEachVoxel([&](uint64_t i, int32_t x, int32_t y, int32_t z) {
    keep[i] = (x + y + z) % 2;
    if (keep[i]) expected.insert({z, y, x});
  });
  EXPECT_EQ(ToKeys(s.Filter(keep)), expected);
}

TEST(VoxelSetTest, BoundsOfEmptyAndNonEmptySets) {
  Index3 lo, hi;
  VoxelSet empty(Dims{4, 4, 4});
  empty.Bounds(&lo, &hi);
  EXPECT_GT(lo.x, hi.x);
  VoxelSet s = VoxelSet::FromIndices(Dims{10, 10, 10}, {{2, 3, 4}, {7, 1, 5}});
  s.Bounds(&lo, &hi);
  EXPECT_EQ(lo, (Index3{2, 1, 4}));
  EXPECT_EQ(hi, (Index3{7, 3, 5}));
}

TEST(VoxelSetTest, CropKeepsTheBoxsVoxelsInItsOwnFrame) {
  std::vector<Index3> all;
  for (int z = 0; z < 9; ++z)
    for (int y = 0; y < 7; ++y)
      for (int x = 0; x < 11; ++x)
        if ((x * 7 + y * 3 + z * 5) % 4 != 0) all.push_back({x, y, z});
  const VoxelSet set = VoxelSet::FromIndices({11, 7, 9}, all);
  // A box reaching past the set's on two sides.
  const Index3 lo{-2, 3, 4};
  const Dims box{6, 6, 8};
  const VoxelSet crop = set.Crop(lo, box);
  EXPECT_EQ(crop.dims(), box);
  std::vector<Index3> want;
  for (const Index3& p : all) {
    const Index3 q{p.x - lo.x, p.y - lo.y, p.z - lo.z};
    if (box.Contains(q.x, q.y, q.z)) want.push_back(q);
  }
  std::sort(want.begin(), want.end(), [](const Index3& a, const Index3& b) {
    return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
  });
  EXPECT_EQ(crop.ToIndices(), want);
  EXPECT_TRUE(set.Crop({20, 0, 0}, {4, 4, 4}).empty());
}

}  // namespace
}  // namespace sheetmesh
