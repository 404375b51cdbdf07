// The local SCVD (ScvdOptions::local): a brick of the volume with a halo builds, in its
// core, the cells the whole volume builds — the property bricked sheet stages rest on.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <tuple>
#include <vector>

#include "tests/testing/preset_sheets.h"
#include "tests/testing/status_matchers.h"
#include "worker/pipeline/scvd/local_seeds.h"
#include "worker/pipeline/scvd/scvd.h"
#include "worker/pipeline/voxel/sheet_analysis.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::PresetSheets;
using ::sheetmesh::testing::StatusIs;
using ::testing::HasSubstr;

struct Diagram {
  SheetAnalysis sheet;
  Scvd scvd;
};

Diagram Local(VoxelSet set, const Index3& origin, double r, double thickness, int steps,
              uint64_t seed = 1, bool spaced = true) {
  Diagram d;
  absl::StatusOr<SheetAnalysis> a = AnalyzeSheet(std::move(set));
  EXPECT_TRUE(a.ok()) << a.status();
  d.sheet = std::move(a).value();
  ScvdOptions o;
  o.local = true;
  o.origin = origin;
  o.radius_voxels = r;
  o.mean_thickness_voxels = thickness;
  o.lloyd_max_iter = steps;
  o.seed = seed;
  o.local_spacing = spaced;
  absl::StatusOr<Scvd> s = BuildScvd(d.sheet.set, d.sheet.neighbors, d.sheet.components,
                                     d.sheet.thickness_stats.mean, o);
  EXPECT_TRUE(s.ok()) << s.status();
  d.scvd = std::move(s).value();
  return d;
}

// The voxels of the core box [lo, lo + size) whose cell's generator (by its global
// position) differs between the whole and a brick of core and halo.
struct Mismatch {
  uint64_t core_voxels = 0;
  uint64_t differ = 0;
};

Mismatch CompareCore(const Diagram& whole, const Index3& lo, const Dims& size, int halo, double r,
                     int steps) {
  const Dims& d = whole.sheet.set.dims();
  const Index3 blo{std::max(0, lo.x - halo), std::max(0, lo.y - halo), std::max(0, lo.z - halo)};
  const Index3 bhi{std::min<int>(d.nx, lo.x + size.nx + halo),
                   std::min<int>(d.ny, lo.y + size.ny + halo),
                   std::min<int>(d.nz, lo.z + size.nz + halo)};
  const Dims bdims{bhi.x - blo.x, bhi.y - blo.y, bhi.z - blo.z};
  if (whole.sheet.set.Crop(lo, size).empty()) return {};
  const Diagram brick =
      Local(whole.sheet.set.Crop(blo, bdims), blo, r, whole.sheet.thickness_stats.mean, steps);
  Mismatch m;
  whole.sheet.set.ForEachVoxel([&](uint64_t v, int32_t x, int32_t y, int32_t z) {
    if (x < lo.x || y < lo.y || z < lo.z || x >= lo.x + size.nx || y >= lo.y + size.ny ||
        z >= lo.z + size.nz) {
      return;
    }
    ++m.core_voxels;
    const Index3 g = whole.scvd.generators[whole.scvd.cell[v]];
    const int64_t bv = brick.sheet.set.Find(x - blo.x, y - blo.y, z - blo.z);
    const Index3 b = brick.scvd.generators[brick.scvd.cell[bv]];
    if (b.x + blo.x != g.x || b.y + blo.y != g.y || b.z + blo.z != g.z) ++m.differ;
  });
  return m;
}

// Measured over r = 3, 7, 12 and 3 to 20 Lloyd steps on three presets (bench/RESULTS.md):
// the core's cells equal the whole's once the halo is about 7 r; a thick slab grown over
// columns reaches further with every step.
TEST(ScvdLocalTest, ABrickWithAHaloBuildsTheWholeVolumesCellsInItsCore) {
  const VoxelSet sheets = PresetSheets("rough_network", {200, 200, 160});
  const Dims core{40, 40, 40};
  const Index3 lo{80, 80, 60};
  for (double r : {3.0, 7.0}) {
    const Diagram whole = Local(sheets, {}, r, 0, 8);
    const Mismatch m = CompareCore(whole, lo, core, static_cast<int>(9 * r) + 8, r, 8);
    ASSERT_GT(m.core_voxels, 1000u) << "the core must hold sheet";
    EXPECT_EQ(m.differ, 0u) << "r = " << r;
    // A halo too short for the Lloyd steps' reach gives other cells near the seams: the
    // comparison can fail.
    const Mismatch short_halo = CompareCore(whole, lo, core, 4, r, 8);
    EXPECT_GT(short_halo.differ, 0u) << "r = " << r;
  }
}

TEST(ScvdLocalTest, TheSameVoxelsInAnotherBoxGiveTheSameGlobalDiagram) {
  const VoxelSet sheets = PresetSheets("grazing_sheet", {140, 120, 80});
  // The same voxels 7, 5 and 3 further on in a larger box, read with origin 0, against the
  // original box read with origin (7, 5, 3): the same global voxels, the same generators.
  const Index3 shift{7, 5, 3};
  VoxelSet::Builder b({150, 130, 90});
  sheets.ForEachRun([&](int32_t y, int32_t z, const sheetmesh::Run& run, uint64_t) {
    b.AddRun(y + shift.y, z + shift.z, run.x0 + shift.x, run.x1 + shift.x);
  });
  const Diagram big = Local(std::move(b).Build(), {}, 5, 5.0, 8);
  const Diagram small = Local(sheets, shift, 5, 5.0, 8);
  ASSERT_EQ(big.scvd.num_generators(), small.scvd.num_generators());
  for (uint32_t g = 0; g < big.scvd.num_generators(); ++g) {
    const Index3 p = small.scvd.generators[g];
    EXPECT_EQ(big.scvd.generators[g], (Index3{p.x + shift.x, p.y + shift.y, p.z + shift.z}));
    EXPECT_EQ(big.scvd.centroid[g] - small.scvd.centroid[g], Vec3::Of(shift));
  }
  // Seen from another origin, the same set draws other generators (the hash is of the
  // global position), about as many.
  const Diagram elsewhere = Local(sheets, {3, 0, 0}, 5, 5.0, 8);
  EXPECT_NE(elsewhere.scvd.generators, small.scvd.generators);
  EXPECT_NEAR(double(elsewhere.scvd.num_generators()), double(small.scvd.num_generators()),
              0.15 * small.scvd.num_generators());
}

TEST(ScvdLocalTest, GeneratorsFollowFormula3InExpectation) {
  const VoxelSet sheets = PresetSheets("shallow_network", {160, 160, 120});
  for (bool spaced : {true, false}) {
    for (double r : {2.0, 4.0, 8.0}) {
      const Diagram d = Local(sheets, {}, r, 0, 0, 1, spaced);
      const double expected = double(sheets.size()) / d.scvd.cell_volume;
      // Bernoulli: Poisson, within four standard deviations; spaced: each cube of the
      // grid is off by less than one (well under that in all), plus the components no
      // draw chose.
      EXPECT_NEAR(d.scvd.num_generators(), expected,
                  (spaced ? 1 : 4) * std::sqrt(expected) + d.sheet.components.count())
          << "r = " << r << (spaced ? ", spaced" : ", Bernoulli");
      std::vector<int> per_component(d.sheet.components.count(), 0);
      for (uint32_t c : d.scvd.generator_component) ++per_component[c];
      for (int n : per_component) EXPECT_GE(n, 1) << "every component gets a generator";
      EXPECT_TRUE(std::is_sorted(d.scvd.generator_voxel.begin(), d.scvd.generator_voxel.end()))
          << "ids follow the voxels' order";
    }
  }
}

// Why the draw is spaced: a piece's count spreads like Poisson's when each node draws
// alone, and a lens given one cell instead of two gives no triangle (bench/RESULTS.md).
// Summed over the pieces: (count − voxels / V_vol)², measured a tenth of Bernoulli's.
TEST(ScvdLocalTest, TheSpacedDrawSpreadsFarLessThanPoisson) {
  const VoxelSet sheets = PresetSheets("vuggy_network", {128, 128, 96});
  double spread[2] = {0, 0};
  for (bool spaced : {true, false}) {
    for (uint64_t seed = 1; seed <= 4; ++seed) {
      const Diagram d = Local(sheets, {}, 6, 0, 0, seed, spaced);
      std::vector<double> n(d.sheet.components.count(), 0);
      for (uint32_t c : d.scvd.generator_component) n[c] += 1;
      for (uint32_t c = 0; c < n.size(); ++c) {
        const double e = d.sheet.components.sizes[c] / d.scvd.cell_volume;
        spread[spaced] += (n[c] - e) * (n[c] - e);
      }
    }
  }
  EXPECT_LT(spread[true], 0.25 * spread[false])
      << "spaced " << spread[true] << ", Bernoulli " << spread[false];
}

// The draw's grid: each cube gets floor(W / V + u) generators at its least-hash nodes a
// spacing apart, whatever else the set holds.
TEST(ScvdLocalTest, TheSpacedDrawDependsOnEachCubeAlone) {
  // A plane of nodes, z = 10, 60 × 60, one voxel each, 1 generator per 40.
  LocalDraw draw;
  draw.per_voxel = 1.0 / 40;
  draw.spacing = ExclusionRadius(40, 1, /*columns=*/true);
  EXPECT_NEAR(draw.spacing, std::sqrt(40 / M_PI), 1e-12);
  auto plane = [](int x0, int x1) {
    std::vector<Index3> p;
    for (int y = 0; y < 60; ++y)
      for (int x = x0; x < x1; ++x) p.push_back({x, y, 10});
    return p;
  };
  auto run = [&](const std::vector<Index3>& nodes) {
    const std::vector<uint32_t> ids = StratifiedDraw(draw, [&](const auto& f) {
      for (uint32_t n = 0; n < nodes.size(); ++n) f(n, nodes[n], 1.0);
    });
    std::vector<Index3> out;
    for (uint32_t n : ids) out.push_back(nodes[n]);
    return out;
  };
  const std::vector<Index3> all = run(plane(0, 60));
  EXPECT_NEAR(double(all.size()), 3600.0 / 40, 0.5 * std::sqrt(3600.0 / 40));
  for (size_t i = 0; i < all.size(); ++i) {
    for (size_t j = i + 1; j < all.size(); ++j) {
      const double side = 2 * draw.spacing;
      const bool same_cube = std::floor(all[i].x / side) == std::floor(all[j].x / side) &&
                             std::floor(all[i].y / side) == std::floor(all[j].y / side);
      const double dx = all[i].x - all[j].x, dy = all[i].y - all[j].y;
      if (same_cube) EXPECT_GE(std::hypot(dx, dy), draw.spacing) << "apart within a cube";
      EXPECT_FALSE(all[i] == all[j]);
    }
  }
  // The left part of the plane up to a cube's edge: the same generators there.
  const int edge = static_cast<int>(std::ceil(3 * 2 * draw.spacing));
  std::vector<Index3> left;
  for (const Index3& p : all)
    if (p.x < edge) left.push_back(p);
  std::vector<Index3> part = run(plane(0, edge));
  EXPECT_EQ(part, left);
  // Another seed: others, about as many.
  draw.seed = 2;
  const std::vector<Index3> other = run(plane(0, 60));
  EXPECT_NE(other, all);
  EXPECT_NEAR(double(other.size()), double(all.size()), 0.5 * std::sqrt(3600.0 / 40));
}

TEST(ScvdLocalTest, TheExclusionRadiusHoldsOneCellOfTheSheet) {
  // A slab of thickness t cut by a ball of radius R centred in it: π (R² t − t³ / 12).
  for (double t : {1.0, 3.0, 8.0}) {
    for (double v : {20.0, 300.0, 5000.0}) {
      const double r = ExclusionRadius(v, t, false);
      const double in_slab =
          r >= t / 2 ? M_PI * (r * r * t - t * t * t / 12) : 4.0 / 3.0 * M_PI * r * r * r;
      EXPECT_NEAR(in_slab, v, 1e-9 * v) << "t = " << t << ", voxels = " << v;
    }
  }
}

TEST(ScvdLocalTest, GivenGeneratorsGrowOnceInPositionOrder) {
  const VoxelSet sheets = PresetSheets("grazing_sheet", {140, 120, 80});
  const Diagram whole = Local(sheets, {}, 6, 0, 8);
  auto grow = [&](std::vector<Index3> given) {
    ScvdOptions o;
    o.radius_voxels = 6;
    o.generators = given;
    absl::StatusOr<Scvd> s = BuildScvd(whole.sheet.set, whole.sheet.neighbors,
                                       whole.sheet.components, whole.sheet.thickness_stats.mean, o);
    EXPECT_TRUE(s.ok()) << s.status();
    return std::move(s).value();
  };
  std::vector<Index3> given = whole.scvd.generators;
  const Scvd once = grow(given);
  EXPECT_EQ(once.iterations, 1);
  std::vector<Index3> sorted = whole.scvd.generators;
  std::sort(sorted.begin(), sorted.end(), [](const Index3& a, const Index3& b) {
    return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
  });
  EXPECT_EQ(once.generators, sorted) << "ids in (z, y, x) order";
  // Any order, one twice, one off the sheet: the same diagram.
  std::reverse(given.begin(), given.end());
  given.push_back(given.front());
  given.push_back({0, 0, 0});
  ASSERT_FALSE(whole.sheet.set.Contains(0, 0, 0));
  const Scvd again = grow(given);
  EXPECT_EQ(again.generators, once.generators);
  EXPECT_EQ(again.cell, once.cell);
  for (uint32_t c : once.cell) ASSERT_NE(c, kNoCell) << "every component has a generator";

  ScvdOptions o;
  o.generators = std::vector<Index3>{{0, 0, 0}};
  EXPECT_THAT(BuildScvd(whole.sheet.set, whole.sheet.neighbors, whole.sheet.components,
                        whole.sheet.thickness_stats.mean, o),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("given generators")));
}

TEST(ScvdLocalTest, BadLocalParametersAreInvalidArgument) {
  const VoxelSet sheets = PresetSheets("grazing_sheet", {140, 120, 80});
  absl::StatusOr<SheetAnalysis> a = AnalyzeSheet(sheets);
  ASSERT_TRUE(a.ok()) << a.status();
  ScvdOptions o;
  o.local = true;
  o.origin = {0, -4, 0};
  EXPECT_THAT(BuildScvd(a->set, a->neighbors, a->components, a->thickness_stats.mean, o),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("origin (0, -4, 0)")));
  o.origin = {};
  const std::vector<float> rho(a->set.size(), 1.0f);
  o.density = rho;
  EXPECT_THAT(BuildScvd(a->set, a->neighbors, a->components, a->thickness_stats.mean, o),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("density")));
}

}  // namespace
}  // namespace sheetmesh
