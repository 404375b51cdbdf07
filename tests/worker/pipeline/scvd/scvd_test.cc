#include "worker/pipeline/scvd/scvd.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <vector>

#include "tests/testing/shapes.h"
#include "tests/testing/status_matchers.h"
#include "worker/pipeline/voxel/sheet_analysis.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::PlaneSlab;
using ::sheetmesh::testing::StatusIs;
using ::testing::HasSubstr;

SheetAnalysis Analyze(VoxelSet s) {
  auto a = AnalyzeSheet(std::move(s));
  EXPECT_TRUE(a.ok()) << a.status();
  return std::move(a).value();
}

Scvd Build(const SheetAnalysis& a, double r, uint64_t seed = 1) {
  ScvdOptions o;
  o.radius_voxels = r;
  o.seed = seed;
  auto s = BuildScvd(a.set, a.neighbors, a.components, a.thickness_stats.mean, o);
  EXPECT_TRUE(s.ok()) << s.status();
  return std::move(s).value();
}

TEST(ScvdTest, GeneratorCountFollowsFormula3) {
  EXPECT_DOUBLE_EQ(CellVolume(5.0, 7.0), 5.0 * 85.0);
  EXPECT_EQ(GeneratorsForComponent(4250, 425.0), 10);
  EXPECT_EQ(GeneratorsForComponent(4460, 425.0), 10);  // 10.49 rounds down
  EXPECT_EQ(GeneratorsForComponent(4470, 425.0), 11);
  EXPECT_EQ(GeneratorsForComponent(3, 425.0), 1);  // every component gets one
  const SheetAnalysis a = Analyze(PlaneSlab({64, 64, 16}, {32, 32, 8}, {0, 0, 1}, 5));
  const Scvd s = Build(a, 7);
  EXPECT_EQ(s.num_generators(), GeneratorsForComponent(a.set.size(), CellVolume(5.0, 7.0)));
}

TEST(ScvdTest, GeneratorsStayOnTheSheetAndCellsCoverIt) {
  const SheetAnalysis a = Analyze(testing::CylinderShell({60, 60, 30}, 30, 30, 22, 4, 2, 28));
  const Scvd s = Build(a, 6);
  for (uint32_t g = 0; g < s.num_generators(); ++g) {
    const Index3 p = s.generators[g];
    EXPECT_EQ(a.set.Find(p.x, p.y, p.z), static_cast<int64_t>(s.generator_voxel[g]));
    EXPECT_EQ(s.cell[s.generator_voxel[g]], g) << "a generator lies in its own cell";
  }
  uint64_t total = 0;
  for (uint32_t c : s.cell) ASSERT_NE(c, kNoCell);
  for (uint32_t n : s.cell_size) total += n;
  EXPECT_EQ(total, a.set.size());
}

TEST(ScvdTest, CellsAreConnected) {
  const SheetAnalysis a = Analyze(PlaneSlab({48, 48, 48}, {24, 24, 24}, {1, 2, 3}, 4));
  const Scvd s = Build(a, 5);
  // Flood each cell from its generator inside the cell only: it must reach all its voxels.
  std::vector<uint32_t> reached(s.num_generators(), 0);
  std::vector<uint8_t> seen(a.set.size(), 0);
  for (uint32_t g = 0; g < s.num_generators(); ++g) {
    std::vector<uint32_t> stack = {s.generator_voxel[g]};
    seen[stack[0]] = 1;
    while (!stack.empty()) {
      const uint32_t v = stack.back();
      stack.pop_back();
      ++reached[g];
      for (uint32_t u : a.neighbors.of(v)) {
        if (u != kNoNeighbor && !seen[u] && s.cell[u] == g) {
          seen[u] = 1;
          stack.push_back(u);
        }
      }
    }
    EXPECT_EQ(reached[g], s.cell_size[g]) << "cell " << g;
  }
}

TEST(ScvdTest, SameSeedGivesTheSameDiagramAndAnotherSeedDoesNot) {
  const SheetAnalysis a = Analyze(PlaneSlab({64, 64, 16}, {32, 32, 8}, {0, 0, 1}, 5));
  const Scvd s1 = Build(a, 6, 42), s2 = Build(a, 6, 42), s3 = Build(a, 6, 43);
  EXPECT_EQ(s1.generator_voxel, s2.generator_voxel);
  EXPECT_EQ(s1.cell, s2.cell);
  EXPECT_NE(s1.generator_voxel, s3.generator_voxel);
}

TEST(ScvdTest, SimultaneousArrivalGoesToTheLowerId) {
  // A line of 5 voxels; seeds at both ends reach the middle in the same round.
  const VoxelSet line =
      VoxelSet::FromIndices({5, 1, 1}, {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {4, 0, 0}});
  SM_ASSERT_OK_AND_ASSIGN(NeighborTable nt, NeighborTable::Build(line));
  const std::vector<uint32_t> seeds_a = {4, 0};  // cell 0 at x=4, cell 1 at x=0
  SM_ASSERT_OK_AND_ASSIGN(std::vector<uint32_t> cell, GrowCells(nt, seeds_a));
  EXPECT_THAT(cell, ::testing::ElementsAre(1, 1, 0, 0, 0));
  const std::vector<uint32_t> seeds_b = {0, 4};
  SM_ASSERT_OK_AND_ASSIGN(cell, GrowCells(nt, seeds_b));
  EXPECT_THAT(cell, ::testing::ElementsAre(0, 0, 0, 1, 1));
}

// The growth runs each round on all cores; its cells are those of a plain one-thread
// breadth-first growth (first to arrive, lowest id among simultaneous arrivals), on one
// thread and on several.
TEST(ScvdTest, GrowingOnAllCoresGivesThePlainGrowthsCells) {
  const SheetAnalysis a = Analyze(PlaneSlab({200, 200, 12}, {100, 100, 6}, {0, 0, 1}, 6));
  const uint32_t n = static_cast<uint32_t>(a.neighbors.size());
  ASSERT_GT(n, 100000u);
  std::vector<uint32_t> seeds;
  for (uint32_t v = 7; v < n && seeds.size() < 600; v += n / 600 + 13) seeds.push_back(v);
  // The plain growth, round by round.
  std::vector<uint32_t> expected(n, kNoCell), arrived(n, 0);
  std::vector<uint32_t> frontier, next;
  for (uint32_t i = 0; i < seeds.size(); ++i) {
    expected[seeds[i]] = i;
    frontier.push_back(seeds[i]);
  }
  for (uint32_t r = 1; !frontier.empty(); ++r) {
    next.clear();
    for (uint32_t v : frontier) {
      for (uint32_t u : a.neighbors.of(v)) {
        if (u == kNoNeighbor) continue;
        if (expected[u] == kNoCell) {
          expected[u] = expected[v];
          arrived[u] = r;
          next.push_back(u);
        } else if (arrived[u] == r) {
          expected[u] = std::min(expected[u], expected[v]);
        }
      }
    }
    frontier.swap(next);
  }
  for (int threads : {1, 2, 4}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    SM_ASSERT_OK_AND_ASSIGN(const std::vector<uint32_t> cell, GrowCells(a.neighbors, seeds));
    EXPECT_EQ(cell, expected) << threads << " threads";
  }
}

TEST(ScvdTest, LloydLowersTheEnergyAndAdjacencyIsSymmetricAndReal) {
  const SheetAnalysis a = Analyze(PlaneSlab({64, 64, 16}, {32, 32, 8}, {0, 0, 1}, 5));
  const Scvd s = Build(a, 7);
  ASSERT_GE(s.energy.size(), 2u);
  EXPECT_LT(s.energy.back(), s.energy.front());
  for (const auto& [p, q] : s.adjacency) {
    EXPECT_LT(p, q);
    // Some face of cell p touches cell q.
    bool touch = false;
    for (uint32_t v = 0; v < a.set.size() && !touch; ++v) {
      if (s.cell[v] != p) continue;
      for (uint32_t u : a.neighbors.of(v)) touch |= u != kNoNeighbor && s.cell[u] == q;
    }
    EXPECT_TRUE(touch) << p << "-" << q;
  }
}

TEST(ScvdTest, EveryComponentGetsAtLeastOneGenerator) {
  const Dims d{40, 40, 12};
  const VoxelSet s = Union(PlaneSlab(d, {20, 20, 6}, {0, 0, 1}, 3, 4),
                           VoxelSet::FromIndices(d, {{1, 1, 1}, {2, 1, 1}}));
  const SheetAnalysis a = Analyze(s);
  const Scvd scvd = Build(a, 6);
  std::vector<int> per(a.components.count(), 0);
  for (uint32_t c : scvd.generator_component) ++per[c];
  for (int n : per) EXPECT_GE(n, 1);
}

TEST(ScvdTest, BadParametersAreInvalidArgument) {
  const SheetAnalysis a = Analyze(PlaneSlab({32, 32, 8}, {16, 16, 4}, {0, 0, 1}, 3));
  ScvdOptions o;
  o.radius_voxels = 0;
  EXPECT_THAT(BuildScvd(a.set, a.neighbors, a.components, 3, o),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("r = 0")));
  o.radius_voxels = -2;
  EXPECT_THAT(BuildScvd(a.set, a.neighbors, a.components, 3, o),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("positive")));
  o.radius_voxels = 500;
  EXPECT_THAT(BuildScvd(a.set, a.neighbors, a.components, 3, o),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("exceeds")));
  o.radius_voxels = 5;
  EXPECT_THAT(BuildScvd(a.set, a.neighbors, a.components, 0, o),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("thickness")));
  o.generator_count = 1;
  const VoxelSet two = Union(a.set, VoxelSet::FromIndices({32, 32, 8}, {{0, 0, 0}}));
  const SheetAnalysis b = Analyze(two);
  EXPECT_THAT(BuildScvd(b.set, b.neighbors, b.components, 3, o),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("components")));
  EXPECT_THAT(AnalyzeSheet(VoxelSet(Dims{4, 4, 4})), StatusIs(absl::StatusCode::kInvalidArgument));
}

TEST(ScvdTest, UserGeneratorCountIsSpreadOverComponents) {
  const SheetAnalysis a = Analyze(PlaneSlab({64, 64, 16}, {32, 32, 8}, {0, 0, 1}, 5));
  ScvdOptions o;
  o.generator_count = 25;
  SM_ASSERT_OK_AND_ASSIGN(Scvd s, BuildScvd(a.set, a.neighbors, a.components, 5, o));
  EXPECT_EQ(s.num_generators(), 25u);
}

TEST(ScvdTest, DensityMakesCellsSmallerWhereItIsLarger) {
  // Formula 2 with ρ = 9 on the half x < 48 of a slab and 1 on the rest.
  const SheetAnalysis a = Analyze(PlaneSlab({96, 48, 12}, {48, 24, 6}, {0, 0, 1}, 3));
  std::vector<float> rho(a.set.size());
  a.set.ForEachVoxel([&](uint64_t v, int32_t x, int32_t, int32_t) { rho[v] = x < 48 ? 9 : 1; });
  ScvdOptions o;
  o.radius_voxels = 4;
  o.density = rho;
  SM_ASSERT_OK_AND_ASSIGN(Scvd s,
                          BuildScvd(a.set, a.neighbors, a.components, a.thickness_stats.mean, o));
  const Scvd plain = Build(a, 4);
  EXPECT_EQ(s.num_generators(), plain.num_generators()) << "the same budget";
  auto left = [](const Scvd& d) {
    size_t n = 0;
    for (const Index3& g : d.generators) n += g.x < 48;
    return double(n) / d.num_generators();
  };
  EXPECT_NEAR(left(plain), 0.5, 0.08);
  EXPECT_GT(left(s), 0.6) << "sqrt 9 = 3 times the generators per area on the dense half";
  // A density that does not match the set, or is not positive, is refused.
  o.density = std::span<const float>(rho).first(rho.size() - 1);
  EXPECT_THAT(BuildScvd(a.set, a.neighbors, a.components, 3, o),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("density")));
  rho[7] = 0;
  o.density = rho;
  EXPECT_THAT(BuildScvd(a.set, a.neighbors, a.components, 3, o),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("density 0")));
}

}  // namespace
}  // namespace sheetmesh
