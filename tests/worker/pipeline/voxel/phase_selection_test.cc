#include "worker/pipeline/voxel/phase_selection.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/testing/status_matchers.h"
#include "worker/pipeline/volume/volume_open.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::StatusIs;
using ::testing::HasSubstr;

// Serves a DenseVolume through the VolumeSource interface.
class DenseSource : public VolumeSource {
 public:
  explicit DenseSource(DenseVolume v) : v_(std::move(v)) {
    info_ = v_.info;
    info_.path = "mem.raw";
  }
  absl::Status ReadSlices(int64_t z0, int64_t count, std::span<std::byte> out) override {
    const size_t slice = v_.data.size() / v_.info.dims.nz;
    std::copy(v_.data.begin() + z0 * slice, v_.data.begin() + (z0 + count) * slice, out.begin());
    return absl::OkStatus();
  }

 private:
  DenseVolume v_;
};

DenseVolume Ramp(DType dtype) {
  DenseVolume v = DenseVolume::Zeros({10, 4, 3}, dtype);
  for (int z = 0; z < 3; ++z)
    for (int y = 0; y < 4; ++y)
      for (int x = 0; x < 10; ++x) v.Set(x, y, z, x);  // value = x
  return v;
}

TEST(PhaseSelectionTest, LabelsWindowAndNonZeroSelectTheRightVoxels) {
  for (DType t : {DType::kUInt8, DType::kUInt16, DType::kFloat32}) {
    DenseSource src(Ramp(t));
    SM_ASSERT_OK_AND_ASSIGN(VoxelSet labels, SelectPhase(src, PhaseSelection::Labels({2, 7})));
    EXPECT_EQ(labels.size(), 2u * 12);
    EXPECT_TRUE(labels.Contains(7, 3, 2));
    SM_ASSERT_OK_AND_ASSIGN(VoxelSet window, SelectPhase(src, PhaseSelection::Window(3, 5)));
    EXPECT_EQ(window.size(), 3u * 12);
    EXPECT_EQ(window.num_runs(), 12);
    SM_ASSERT_OK_AND_ASSIGN(VoxelSet nz, SelectPhase(src, PhaseSelection::NonZero()));
    EXPECT_EQ(nz.size(), 9u * 12);
  }
}

TEST(PhaseSelectionTest, MaskRestrictsTheSelection) {
  DenseSource src(Ramp(DType::kUInt8));
  const VoxelSet mask = VoxelSet::FromIndices({10, 4, 3}, {{5, 0, 0}, {6, 0, 0}, {0, 1, 1}});
  SelectionStats stats;
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet s,
                          SelectPhase(src, PhaseSelection::Window(4, 6), &mask, &stats));
  EXPECT_EQ(s.size(), 2u);
  EXPECT_EQ(stats.outside_mask, 3u * 12 - 2);
  const VoxelSet wrong(Dims{3, 3, 3});
  EXPECT_THAT(SelectPhase(src, PhaseSelection::NonZero(), &wrong),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("mask dims")));
}

TEST(PhaseSelectionTest, EmptySelectionNamesFileSelectionAndValueRange) {
  DenseSource src(Ramp(DType::kUInt8));
  SelectionStats stats;
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet s, SelectPhase(src, PhaseSelection::Labels({42}), nullptr, &stats));
  EXPECT_TRUE(s.empty());
  EXPECT_THAT(CheckNotEmpty(s, src.info(), PhaseSelection::Labels({42}), stats),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       ::testing::AllOf(HasSubstr("mem.raw"), HasSubstr("labels=42"),
                                        HasSubstr("from 0 to 9"))));
}

TEST(PhaseSelectionTest, ParsesTheWrittenForms) {
  struct Case {
    const char* text;
    bool ok;
    const char* round_trip;
  };
  const Case cases[] = {
      {"nonzero", true, "nonzero"},         {"labels=2,3", true, "labels=2,3"},
      {"255", true, "labels=255"},          {"window=100:200", true, "window=100:200"},
      {"0.5:1.5", true, "window=0.5:1.5"},  {"window=5:1", false, ""},
      {"labels=a", false, ""},              {"labels=", false, ""},
      {"window=1", false, ""},
  };
  for (const Case& c : cases) {
    const auto r = ParsePhaseSelection(c.text);
    EXPECT_EQ(r.ok(), c.ok) << c.text;
    if (r.ok()) EXPECT_EQ(r->ToString(), c.round_trip);
    if (!r.ok()) EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  }
}

}  // namespace
}  // namespace sheetmesh
