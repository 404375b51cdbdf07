#include "common/progress_line.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace sheetmesh {

std::string ProgressLine::StageText(int index, int count, absl::string_view stage, double fraction,
                                    absl::Duration left, bool percent) {
  if (index <= 0) return "starting";
  std::string s = absl::StrFormat("stage %d/%d %s", index, count, stage);
  if (percent) absl::StrAppendFormat(&s, " %3.0f%%", 100 * std::clamp(fraction, 0.0, 1.0));
  if (left != absl::InfiniteDuration()) {
    const int64_t seconds = absl::ToInt64Seconds(left + absl::Milliseconds(500));
    if (seconds >= 60) {
      absl::StrAppendFormat(&s, "  about %d min %02d s left", seconds / 60, seconds % 60);
    } else {
      absl::StrAppendFormat(&s, "  about %d s left", seconds);
    }
  }
  return s;
}

void ProgressLine::Show(absl::string_view label, int index, int count, absl::string_view stage,
                        double fraction, absl::Time now) {
  fraction = std::clamp(fraction, 0.0, 1.0);
  const bool new_stage = index != index_ || stage != stage_;
  if (new_stage) {
    index_ = index;
    stage_ = std::string(stage);
    stage_start_ = now;
    tenth_ = -1;
  }
  absl::Duration left = absl::InfiniteDuration();
  const absl::Duration spent = now - stage_start_;
  if (fraction >= 0.1 && fraction < 1 && spent >= absl::Seconds(1)) {
    left = spent * ((1 - fraction) / fraction);
  }
  if (terminal_) {
    // At most ten redraws a second, and every stage's first.
    if (!new_stage && now - drawn_ < absl::Milliseconds(100)) return;
    drawn_ = now;
    constexpr int kWidth = 30;
    const int fill = static_cast<int>(std::floor(fraction * kWidth));
    out_ << absl::StrFormat("\r%s%s[%s%s] %-60s", label, label.empty() ? "" : " ",
                            std::string(fill, '#'), std::string(kWidth - fill, ' '),
                            StageText(index, count, stage, fraction, left))
         << std::flush;
    open_ = true;
    return;
  }
  const int tenth = static_cast<int>(std::floor(fraction * 10));
  if (!new_stage && tenth == tenth_) return;
  tenth_ = tenth;
  out_ << label << (label.empty() ? "" : " ") << StageText(index, count, stage, fraction, left)
       << std::endl;
}

void ProgressLine::Finish(absl::string_view state) {
  if (terminal_ && open_) {
    out_ << absl::StrFormat("\r%-100s\r", "");
    open_ = false;
  }
  if (!state.empty()) out_ << state << std::endl;
}

}  // namespace sheetmesh
