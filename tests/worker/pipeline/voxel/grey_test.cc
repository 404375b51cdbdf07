// Grey levels and sheets found on them, on volumes with known answers (tests/testing/
// grey_phantoms.h).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/testing/grey_phantoms.h"
#include "tests/testing/status_matchers.h"
#include "worker/pipeline/voxel/components.h"
#include "worker/pipeline/voxel/grey_volume.h"
#include "worker/pipeline/voxel/sheetness.h"

namespace sheetmesh {
namespace {

using testing::GreyPhantomOptions;
using testing::GreySheet;
using ::testing::HasSubstr;

GreyPhantomOptions OneSheet(double aperture, double sigma, double cnr, Vec3 normal = {0, 0, 1}) {
  GreyPhantomOptions o;
  GreySheet s;
  s.center = {29, 24, 24};
  s.normal = Normalized(normal);
  s.along = Normalized(Cross(s.normal, Vec3(0, 1, 0.3)));
  s.aperture = aperture;
  o.sheets = {s};
  o.psf_sigma = sigma;
  o.cnr = cnr;
  return o;
}

TEST(GreyLevelsTest, RockVoidAndNoiseFromTheHistogram) {
  for (double cnr : {5.0, 10.0, 20.0}) {
    const GreyVolume g = testing::MakeGreyPhantom(OneSheet(1, 1, cnr));
    SM_ASSERT_OK_AND_ASSIGN(GreyLevels l, MeasureGreyLevels(g, {}, {}, "g.raw"));
    const double noise = 160 / cnr;
    EXPECT_NEAR(l.rock, 200, 0.25 * noise) << cnr;
    EXPECT_NEAR(l.noise, noise, 0.3 * noise) << cnr;
    EXPECT_TRUE(l.rock_measured);
    if (cnr >= 10) {
      EXPECT_NEAR(l.void_level, 40, 0.5 * noise) << cnr;
      EXPECT_TRUE(l.void_measured);
      EXPECT_EQ(l.problem, "");
    } else if (l.void_measured) {
      // At CNR 5 the void's peak may drown in the partial voxels between it and the rock;
      // then it is said, never taken from elsewhere.
      EXPECT_NEAR(l.void_level, 40, 0.5 * noise);
    } else {
      EXPECT_THAT(l.problem, HasSubstr("no void phase"));
    }
  }
}

// One sheet in rock with no band of void beside it: the histogram has no void peak.
GreyVolume WithoutVoid(double aperture, double sigma, double cnr) {
  GreyPhantomOptions o = OneSheet(aperture, sigma, cnr);
  o.void_band = 0;
  return testing::MakeGreyPhantom(o);
}

// A sheet's partial voxels, even a 2-voxel sheet's dark core, are not a void phase: no
// void is taken from them (a wrong void would bias every aperture).
TEST(GreyLevelsTest, ASheetsCoreIsNotTakenForTheVoid) {
  const GreyVolume g = WithoutVoid(2, 0.5, 10);
  SM_ASSERT_OK_AND_ASSIGN(GreyLevels l, MeasureGreyLevels(g, {}, {}, "g.raw"));
  EXPECT_FALSE(l.void_measured) << "void at " << l.void_level;
  EXPECT_THAT(l.problem, HasSubstr("no void phase"));
}

TEST(GreyLevelsTest, GivenLevelsAreKeptAndAMissingVoidIsSaid) {
  const GreyVolume g = WithoutVoid(1, 1, 10);
  SM_ASSERT_OK_AND_ASSIGN(GreyLevels none, MeasureGreyLevels(g, {}, {}, "g.raw"));
  EXPECT_THAT(none.problem, HasSubstr("no void phase in the histogram"));
  SM_ASSERT_OK_AND_ASSIGN(GreyLevels given, MeasureGreyLevels(g, 40.0, std::nullopt, "g.raw"));
  EXPECT_EQ(given.void_level, 40);
  EXPECT_FALSE(given.void_measured);
  EXPECT_EQ(given.problem, "");
}

TEST(GreyLevelsTest, VolumesWithoutGreyLevelsAreRefusedNamingWhy) {
  GreyVolume g;
  g.dims = {8, 8, 8};
  g.values.assign(512, 7.f);
  EXPECT_THAT(
      MeasureGreyLevels(g, {}, {}, "flat.raw"),
      testing::StatusIs(absl::StatusCode::kInvalidArgument,
                        HasSubstr("flat.raw: input.grey needs contrast, and every voxel is 7")));
  for (size_t i = 0; i < g.values.size(); ++i) g.values[i] = float(i % 3);
  EXPECT_THAT(MeasureGreyLevels(g, {}, {}, "labels.raw"),
              testing::StatusIs(absl::StatusCode::kInvalidArgument,
                                HasSubstr("only 3 values (0, 1, 2): a segmented or label volume; "
                                          "select its sheet phase with input.labels")));
  for (size_t i = 0; i < g.values.size(); ++i) g.values[i] = float(i % 97) * 1.5f;
  EXPECT_THAT(
      MeasureGreyLevels(g, 100.0, 50.0, "g.raw"),
      testing::StatusIs(absl::StatusCode::kInvalidArgument,
                        HasSubstr("grey.levels = [100, 50]: the void's level must be below")));
}

// Every aperture from 0.2 to 4 voxels, blurred and noisy, tilted: one sheet, across the
// box; next to nothing away from it, along the void's edge or in the noise.
TEST(SheetnessTest, ThinSheetsAreFoundWholeAndNothingElse) {
  for (double a : {0.2, 0.5, 1.0, 2.0, 4.0}) {
    for (double sigma : {0.5, 1.5}) {
      const double cnr = a < 0.5 ? 20 : 5;
      const GreyPhantomOptions o = OneSheet(a, sigma, cnr, {0.2, 0.3, 1});
      const GreyVolume g = testing::MakeGreyPhantom(o);
      SheetnessStats stats;
      SM_ASSERT_OK_AND_ASSIGN(VoxelSet set, DetectSheets(g, {}, &stats));
      SCOPED_TRACE(absl::StrCat("aperture ", a, ", sigma ", sigma, ", cnr ", cnr));
      SM_ASSERT_OK_AND_ASSIGN(const Components c, LabelComponents(set, Connectivity::k6));
      ASSERT_GE(c.count(), 1u);
      // The largest piece is the sheet, and it crosses the box.
      EXPECT_GE(c.sizes[0], 0.9 * set.size());
      int64_t lo = 1 << 20, hi = -1, astray = 0;
      for (uint64_t i = 0; i < set.size(); ++i) {
        const Index3 p = set.CoordOf(i);
        const Vec3 q(p.x, p.y, p.z);
        if (std::abs(o.sheets[0].Offset(q)) > 0.5 * a + 2 * sigma + 1.5 || p.x < o.void_band - 1) {
          ++astray;
        }
        lo = std::min<int64_t>(lo, p.y);
        hi = std::max<int64_t>(hi, p.y);
      }
      // A few voxels of noise next to the sheet may join it through the low threshold.
      EXPECT_LE(astray, 0.01 * set.size());
      EXPECT_LE(lo, 2);
      EXPECT_GE(hi, 45);
    }
  }
}

// Slab by slab, the answer of the whole volume at once: cut into slabs of a few slices
// (each with its halo), the same voxels, to the bit; the noise units measured on a third
// of the slabs, nearly the same.
TEST(SheetnessTest, SlabsGiveTheWholeVolumesAnswer) {
  GreyPhantomOptions o = OneSheet(0.5, 1.0, 8, {0.3, 0.2, 1});
  o.sheets.push_back(o.sheets[0]);
  o.sheets[1].normal = Normalized(Vec3(1, 0.1, 0.2));
  o.sheets[1].aperture = 1.5;
  const GreyVolume g = testing::MakeGreyPhantom(o);
  SheetnessStats whole_stats, slab_stats, sampled_stats;
  SheetnessOptions whole_volume;
  whole_volume.scales = {0.75, 1.5};
  SM_ASSERT_OK_AND_ASSIGN(const VoxelSet whole, DetectSheets(g, whole_volume, &whole_stats));
  EXPECT_EQ(whole_stats.slabs, 1u);
  SheetnessOptions slabs = whole_volume;
  slabs.slab_voxels = 48 * 48 * 26;  // cores of 16 slices (a halo of 5): 3 slabs
  SM_ASSERT_OK_AND_ASSIGN(const VoxelSet sliced, DetectSheets(g, slabs, &slab_stats));
  EXPECT_EQ(slab_stats.slabs, 3u);
  EXPECT_EQ(slab_stats.noise_slices, 48);
  EXPECT_EQ(slab_stats.noise, whole_stats.noise);
  EXPECT_EQ(sliced.size(), whole.size());
  EXPECT_TRUE(sliced == whole);
  slabs.noise_sample_voxels = 48 * 48 * 8;  // 2 blocks of 4 slices of the 48
  SM_ASSERT_OK_AND_ASSIGN(const VoxelSet sampled, DetectSheets(g, slabs, &sampled_stats));
  EXPECT_EQ(sampled_stats.noise_slices, 8);
  for (size_t k = 0; k < whole_stats.noise.size(); ++k) {
    EXPECT_NEAR(sampled_stats.noise[k], whole_stats.noise[k], 0.25 * whole_stats.noise[k]) << k;
  }
  uint64_t common = 0;
  sampled.ForEachRun([&](int32_t y, int32_t z, const sheetmesh::Run& run, uint64_t) {
    for (int32_t x = run.x0; x < run.x1; ++x) common += whole.Contains(x, y, z);
  });
  EXPECT_GE(common, 0.9 * whole.size()) << sampled.size() << " of " << whole.size();
  EXPECT_LE(sampled.size(), 1.1 * whole.size());
}

TEST(SheetnessTest, BadOptionsAreRefusedNamingThem) {
  const GreyVolume g = testing::MakeGreyPhantom(OneSheet(1, 1, 10));
  SheetnessOptions o;
  o.scales = {};
  EXPECT_THAT(DetectSheets(g, o, nullptr),
              testing::StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("grey.scales")));
  o = {};
  o.low = 8;
  EXPECT_THAT(DetectSheets(g, o, nullptr),
              testing::StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("grey.low = 8")));
}

}  // namespace
}  // namespace sheetmesh
