#include "worker/pipeline/voxel/threshold.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <random>

#include "tests/testing/status_matchers.h"
#include "worker/pipeline/volume/volume_open.h"
#include "worker/pipeline/voxel/sheet_input.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::StatusIs;
using ::testing::AllOf;
using ::testing::HasSubstr;

// `v` written as a raw file named `name` in the test's temporary folder; its path.
std::string WriteRawVolume(DenseVolume& v, const Dims& d, const std::string& name) {
  const std::string path = ::testing::TempDir() + "/" + name;
  v.info.dims = d;
  auto sink = CreateVolumeWriter(path, v.info, VolumeFormat::kRaw);
  EXPECT_TRUE(sink.ok()) << sink.status();
  if (sink.ok()) EXPECT_TRUE(WriteDense(v, **sink).ok());
  return path;
}

// Two separated classes: the threshold lies between them.
TEST(ThresholdTest, OtsuSplitsTwoClassesBetweenThem) {
  std::vector<uint64_t> h(256, 0);
  h[40] = 1000;
  h[41] = 500;
  h[200] = 300;
  const double t = OtsuOfHistogram(h, -0.5, 1.0);
  EXPECT_GT(t, 41);
  EXPECT_LT(t, 200);
  // The middle of the empty stretch between the classes: (41 + 199) / 2 + 0.5.
  EXPECT_DOUBLE_EQ(t, 120.5);
}

// The classic worked case: the between-class variance of a three-level histogram peaks
// at the split that isolates the smallest, farthest class.
TEST(ThresholdTest, OtsuOfThreeLevelsPicksTheLargestBetweenClassVariance) {
  std::vector<uint64_t> h = {10, 0, 10, 0, 0, 0, 0, 0, 0, 20};
  // Splits after 0: w 10/30, means 0 and 6.0 -> 10*30*36 = 10800.
  // After 2: w 20/20, means 1 and 9 -> 20*20*64 = 25600 (best).
  // Splits after 2..8 tie: the middle one (5), whose upper edge is 6.
  EXPECT_DOUBLE_EQ(OtsuOfHistogram(h, 0.0, 1.0), 6.0);
}

TEST(ThresholdTest, OneValueHasNoSplit) {
  std::vector<uint64_t> h(16, 0);
  h[5] = 99;
  EXPECT_DOUBLE_EQ(OtsuOfHistogram(h, 0.0, 1.0), 0.0);
}

// A grayscale float volume: dark sheets (60) in bright rock (180) with noise. Otsu's
// threshold recovers the sheet voxels; the default selection is refused with the advice.
TEST(ThresholdTest, OtsuSelectsTheDarkSheetOfANoisyScan) {
  const Dims d{40, 30, 20};
  DenseVolume v = DenseVolume::Zeros(d, DType::kFloat32);
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0, 12);
  int64_t truth = 0;
  for (int64_t z = 0; z < d.nz; ++z)
    for (int64_t y = 0; y < d.ny; ++y)
      for (int64_t x = 0; x < d.nx; ++x) {
        const bool sheet = z == 9 || z == 10 || x == 20;
        truth += sheet;
        v.Set(x, y, z, (sheet ? 60.0 : 180.0) + noise(rng));
      }
  const std::string path = WriteRawVolume(v, d, "gray_40x30x20_f32.raw");

  SheetInput in;
  in.path = path;
  EXPECT_THAT(LoadSheetPhase(in),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("--threshold=otsu")));
  in.threshold = "otsu";
  auto phase = LoadSheetPhase(in);
  ASSERT_TRUE(phase.ok()) << phase.status();
  ASSERT_TRUE(phase->threshold.has_value());
  EXPECT_GT(*phase->threshold, 90);
  EXPECT_LT(*phase->threshold, 150);
  EXPECT_EQ(static_cast<int64_t>(phase->sheet.size()), truth);  // 5 sigma apart: exact
  // The bright side is the rock, most of the volume: no sheet phase.
  in.threshold_above = true;
  EXPECT_THAT(LoadSheetPhase(in),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       AllOf(HasSubstr("gray_40x30x20_f32.raw"), HasSubstr("% of the 24000 voxels"),
                             HasSubstr("--threshold_above=false"))));
  in.threshold = "100";
  in.threshold_above = false;
  phase = LoadSheetPhase(in);
  ASSERT_TRUE(phase.ok());
  EXPECT_EQ(*phase->threshold, 100);
  in.threshold = "half";
  EXPECT_THAT(LoadSheetPhase(in),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("'half'")));
}

// A segmented volume (sheets 255 in rock 0) read with Otsu's threshold: the dark side is the
// rock, 90% of the box. Refused with the way out; the bright side is the sheets.
TEST(ThresholdTest, OtsuOnASegmentedVolumeRefusesTheRockAsTheSheetPhase) {
  const Dims d{20, 20, 20};
  DenseVolume v = DenseVolume::Zeros(d, DType::kUInt8);
  int64_t sheet = 0;
  for (int64_t z = 0; z < d.nz; ++z)
    for (int64_t y = 0; y < d.ny; ++y)
      for (int64_t x = 0; x < d.nx; ++x)
        if (z == 9 || z == 10) v.Set(x, y, z, 255), ++sheet;
  const std::string path = WriteRawVolume(v, d, "segmented_20x20x20_u8.raw");
  SheetInput in;
  in.path = path;
  in.threshold = "otsu";
  EXPECT_THAT(LoadSheetPhase(in),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       AllOf(HasSubstr("segmented_20x20x20_u8.raw"), HasSubstr("90% of the 8000"),
                             HasSubstr("--threshold_above=true"), HasSubstr("--labels=V"))));
  in.threshold_above = true;
  auto phase = LoadSheetPhase(in);
  ASSERT_TRUE(phase.ok()) << phase.status();
  EXPECT_EQ(static_cast<int64_t>(phase->sheet.size()), sheet);
}

}  // namespace
}  // namespace sheetmesh
