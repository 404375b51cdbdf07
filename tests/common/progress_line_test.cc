#include "common/progress_line.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sstream>

namespace sheetmesh {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

const absl::Time t0 = absl::FromUnixSeconds(1000);

TEST(ProgressLineTest, PipedItWritesALinePerStageAndPerTenth) {
  std::ostringstream out;
  ProgressLine line(out, /*terminal=*/false);
  line.Show("", 1, 3, "read", 0.0, t0);
  line.Show("", 1, 3, "read", 0.05, t0);  // the same tenth: nothing
  line.Show("", 1, 3, "read", 1.0, t0);
  line.Show("", 2, 3, "surface", 0.25, t0);
  line.Show("RUNNING", 3, 3, "write", 0.5, t0);
  line.Finish("done");
  EXPECT_EQ(out.str(),
            "stage 1/3 read   0%\nstage 1/3 read 100%\nstage 2/3 surface  25%\n"
            "RUNNING stage 3/3 write  50%\ndone\n");
}

TEST(ProgressLineTest, TheTimeLeftFollowsTheStagesPace) {
  std::ostringstream out;
  ProgressLine line(out, false);
  line.Show("", 1, 2, "surface", 0.0, t0);
  line.Show("", 1, 2, "surface", 0.25, t0 + absl::Seconds(10));
  line.Show("", 1, 2, "surface", 0.5, t0 + absl::Seconds(100));
  EXPECT_THAT(out.str(), HasSubstr("surface  25%  about 30 s left\n"));
  EXPECT_THAT(out.str(), HasSubstr("surface  50%  about 1 min 40 s left\n"));
  // A new stage starts its own clock: no estimate before a tenth of it.
  line.Show("", 2, 2, "write", 0.05, t0 + absl::Seconds(200));
  EXPECT_THAT(out.str(), HasSubstr("stage 2/2 write   5%\n"));
}

TEST(ProgressLineTest, OnATerminalItRedrawsOneLineAndClearsIt) {
  std::ostringstream out;
  ProgressLine line(out, /*terminal=*/true);
  line.Show("", 1, 2, "read", 0.5, t0);
  line.Show("", 1, 2, "read", 0.6, t0 + absl::Milliseconds(10));  // too soon: not drawn
  line.Show("", 2, 2, "surface", 0.0, t0 + absl::Milliseconds(20));
  line.Finish("");
  const std::string s = out.str();
  EXPECT_THAT(s, HasSubstr("\r[###############               ] stage 1/2 read  50%"));
  EXPECT_THAT(s, Not(HasSubstr("60%")));
  EXPECT_THAT(s, HasSubstr("\r[                              ] stage 2/2 surface   0%"));
  EXPECT_THAT(s, Not(HasSubstr("\n")));
  EXPECT_EQ(s.back(), '\r');
}

TEST(ProgressLineTest, BeforeTheFirstStageItSaysStarting) {
  EXPECT_EQ(ProgressLine::StageText(0, 5, "", 0, absl::InfiniteDuration()), "starting");
}

}  // namespace
}  // namespace sheetmesh
