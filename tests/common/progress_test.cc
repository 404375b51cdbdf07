#include "common/progress.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <mutex>
#include <vector>

#include "tests/testing/status_matchers.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::IsOk;
using ::sheetmesh::testing::StatusIs;

class Recorder : public ProgressObserver {
 public:
  bool OnProgress(absl::string_view stage, double fraction, absl::string_view) override {
    std::lock_guard<std::mutex> lock(mu_);
    stages.emplace_back(stage);
    fractions.push_back(fraction);
    return !stop;
  }
  std::mutex mu_;
  std::vector<std::string> stages;
  std::vector<double> fractions;
  bool stop = false;
};

TEST(ProgressTest, NullProgressIsNeverCancelled) {
  Progress p;
  EXPECT_THAT(p.Update(0.5), IsOk());
  EXPECT_FALSE(p.enabled());
}

TEST(ProgressTest, SubRangesMapOntoTheParentRange) {
  Recorder r;
  Progress p(&r, "scvd");
  Progress half = p.Sub(0.5, 1.0);
  Progress quarter = half.Sub(0.0, 0.5);
  ASSERT_THAT(quarter.Update(1.0), IsOk());
  ASSERT_THAT(half.Update(0.5), IsOk());
  ASSERT_EQ(r.fractions.size(), 2u);
  EXPECT_DOUBLE_EQ(r.fractions[0], 0.75);
  EXPECT_DOUBLE_EQ(r.fractions[1], 0.75);
  EXPECT_EQ(r.stages[0], "scvd");
}

TEST(ProgressTest, ObserverStopBecomesCancelledNamingTheStage) {
  Recorder r;
  r.stop = true;
  Progress p(&r, "extract");
  EXPECT_THAT(p.Update(0.1), StatusIs(absl::StatusCode::kCancelled, ::testing::HasSubstr("extract")));
}

TEST(ProgressTest, TickReportsOnlyEveryStride) {
  Recorder r;
  Progress p(&r, "s");
  for (int i = 0; i < 100; ++i) ASSERT_THAT(p.Tick(i, 100, 10), IsOk());
  EXPECT_EQ(r.fractions.size(), 10u);
}

}  // namespace
}  // namespace sheetmesh
