// The real volumes in ../shared/data read with their known counts.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/testing/shared_data.h"
#include "tests/testing/status_matchers.h"
#include "worker/pipeline/voxel/components.h"
#include "worker/pipeline/voxel/sheet_input.h"
#include "worker/pipeline/voxel/thickness.h"

namespace sheetmesh {
namespace {

TEST(RealDataTest, NetlFractureTiffHasItsKnownCounts) {
  SM_REQUIRE_SHARED_DATA("netl_binary_fracture_small.tif");
  SheetInput in;
  in.path = testing::SharedDataFile("netl_binary_fracture_small.tif");
  in.selection = PhaseSelection::Labels({255});
  SM_ASSERT_OK_AND_ASSIGN(SheetPhase phase, LoadSheetPhase(in));
  EXPECT_EQ(phase.info.dims, (Dims{200, 42, 100}));
  EXPECT_EQ(phase.info.dtype, DType::kUInt8);
  EXPECT_EQ(phase.sheet.size(), 84595u);
  SM_ASSERT_OK_AND_ASSIGN(Components c, LabelComponents(phase.sheet, Connectivity::k6));
  EXPECT_EQ(c.count(), 63u);
  EXPECT_EQ(c.sizes[0], 83277u);
  // The sheet lies in the x-z plane: it is thin along y.
  SM_ASSERT_OK_AND_ASSIGN(std::vector<uint16_t> tau, ComputeThickness(phase.sheet));
  const ThicknessStats ts = SummarizeThickness(tau);
  EXPECT_GT(ts.mean, 2.0);
  EXPECT_LT(ts.mean, 6.0);
}

TEST(RealDataTest, DpmJunctionRawReadsWithDimsFromItsName) {
  SM_REQUIRE_SHARED_DATA("dpm_3fractures_100x100x100_u8.raw");
  SheetInput in;
  in.path = testing::SharedDataFile("dpm_3fractures_100x100x100_u8.raw");
  SM_ASSERT_OK_AND_ASSIGN(SheetPhase phase, LoadSheetPhase(in));
  EXPECT_EQ(phase.info.dims, (Dims{100, 100, 100}));
  EXPECT_EQ(phase.stats.max_value, 255);
  // 10.19% of the box.
  EXPECT_NEAR(phase.sheet.size() / 1e6, 0.1019, 0.0005);
  SM_ASSERT_OK_AND_ASSIGN(Components c, LabelComponents(phase.sheet, Connectivity::k6));
  EXPECT_EQ(c.count(), 1u);
}

}  // namespace
}  // namespace sheetmesh
