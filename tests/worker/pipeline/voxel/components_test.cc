#include "worker/pipeline/voxel/components.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "tests/testing/status_matchers.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::StatusIs;

TEST(ComponentsTest, ConnectivityDecidesWhetherDiagonalVoxelsJoin) {
  const Dims d{5, 5, 5};
  // Two voxels sharing an edge, and one more sharing only a corner with the second.
  const VoxelSet s = VoxelSet::FromIndices(d, {{0, 0, 0}, {1, 1, 0}, {2, 2, 1}});
  SM_ASSERT_OK_AND_ASSIGN(Components c6, LabelComponents(s, Connectivity::k6));
  SM_ASSERT_OK_AND_ASSIGN(Components c18, LabelComponents(s, Connectivity::k18));
  SM_ASSERT_OK_AND_ASSIGN(Components c26, LabelComponents(s, Connectivity::k26));
  EXPECT_EQ(c6.count(), 3u);
  EXPECT_EQ(c18.count(), 2u);
  EXPECT_EQ(c26.count(), 1u);
}

TEST(ComponentsTest, LabelsAreOrderedBySizeLargestFirst) {
  const Dims d{20, 5, 5};
  VoxelSet::Builder b(d);
  b.AddRun(0, 0, 0, 2);    // size 2
  b.AddRun(0, 0, 5, 12);   // size 7
  b.AddRun(0, 0, 14, 15);  // size 1
  b.AddRun(2, 3, 0, 4);    // size 4
  const VoxelSet s = std::move(b).Build();
  SM_ASSERT_OK_AND_ASSIGN(Components c, LabelComponents(s, Connectivity::k6));
  EXPECT_THAT(c.sizes, ::testing::ElementsAre(7, 4, 2, 1));
  const std::vector<uint32_t> labels = c.VoxelLabels(s);
  EXPECT_EQ(labels[s.Find(0, 0, 0)], 2u);
  EXPECT_EQ(labels[s.Find(6, 0, 0)], 0u);
  EXPECT_EQ(labels[s.Find(3, 2, 3)], 1u);
}

TEST(ComponentsTest, UShapeJoinsThroughItsBase) {
  const Dims d{10, 10, 3};
  VoxelSet::Builder b(d);
  for (int y = 0; y < 10; ++y) {
    if (y == 9) {
      b.AddRun(y, 0, 0, 10);
    } else {
      b.AddRun(y, 0, 0, 1);
      b.AddRun(y, 0, 9, 10);
    }
  }
  SM_ASSERT_OK_AND_ASSIGN(Components c, LabelComponents(std::move(b).Build(), Connectivity::k6));
  EXPECT_EQ(c.count(), 1u);
  EXPECT_EQ(c.sizes[0], 28u);
}

TEST(ComponentsTest, MatchesFloodFillOnRandomSets) {
  const Dims d{12, 10, 8};
  std::mt19937 rng(9);
  std::vector<Index3> idx;
  for (int i = 0; i < 350; ++i) idx.push_back({int(rng() % 12), int(rng() % 10), int(rng() % 8)});
  const VoxelSet s = VoxelSet::FromIndices(d, idx);
  for (Connectivity conn : {Connectivity::k6, Connectivity::k18, Connectivity::k26}) {
    SM_ASSERT_OK_AND_ASSIGN(Components c, LabelComponents(s, conn));
    // Reference: BFS flood fill over voxel coordinates.
    std::vector<int> label(s.size(), -1);
    std::vector<uint64_t> sizes;
    for (uint64_t start = 0; start < s.size(); ++start) {
      if (label[start] >= 0) continue;
      std::vector<uint64_t> stack = {start};
      label[start] = static_cast<int>(sizes.size());
      uint64_t n = 0;
      while (!stack.empty()) {
        const uint64_t v = stack.back();
        stack.pop_back();
        ++n;
        const Index3 p = s.CoordOf(v);
        for (int dz = -1; dz <= 1; ++dz) {
          for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
              const int nz = (dx != 0) + (dy != 0) + (dz != 0);
              if (nz == 0 || nz > (conn == Connectivity::k6 ? 1 : conn == Connectivity::k18 ? 2 : 3)) {
                continue;
              }
              const int64_t u = s.Find(p.x + dx, p.y + dy, p.z + dz);
              if (u >= 0 && label[u] < 0) {
                label[u] = label[v];
                stack.push_back(u);
              }
            }
          }
        }
      }
      sizes.push_back(n);
    }
    std::sort(sizes.rbegin(), sizes.rend());
    EXPECT_EQ(c.sizes, sizes) << "connectivity " << static_cast<int>(conn);
  }
}

TEST(ComponentsTest, RemoveSmallKeepsComponentsOfAtLeastM) {
  const Dims d{30, 3, 3};
  VoxelSet::Builder b(d);
  b.AddRun(0, 0, 0, 5);
  b.AddRun(0, 0, 10, 13);
  b.AddRun(0, 0, 20, 24);
  SM_ASSERT_OK_AND_ASSIGN(RemovalResult r,
                          RemoveSmallComponents(std::move(b).Build(), 4, Connectivity::k6));
  EXPECT_EQ(r.kept.size(), 9u);
  EXPECT_EQ(r.removed_components, 1u);
  EXPECT_EQ(r.removed_voxels, 3u);
  EXPECT_FALSE(r.kept.Contains(11, 0, 0));
  EXPECT_TRUE(r.kept.Contains(20, 0, 0));
}

TEST(ComponentsTest, UnsupportedConnectivityIsInvalidArgument) {
  EXPECT_THAT(ParseConnectivity(8), StatusIs(absl::StatusCode::kInvalidArgument));
}

}  // namespace
}  // namespace sheetmesh
