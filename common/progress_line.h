// Progress shown to a person: a bar redrawn in place on a terminal, with the stage, how far
// it is and the time it still needs; plain lines on a pipe or in a log (one per stage and
// per tenth of it). The offline CLI and the service's CLI show their jobs this one way.
#ifndef SHEETMESH_COMMON_PROGRESS_LINE_H_
#define SHEETMESH_COMMON_PROGRESS_LINE_H_

#include <ostream>
#include <string>

#include "absl/strings/string_view.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"

namespace sheetmesh {

class ProgressLine {
 public:
  // `terminal`: redraw one line in place (isatty of the stream's descriptor).
  ProgressLine(std::ostream& out, bool terminal) : out_(out), terminal_(terminal) {}

  // Stage `index` of `count` (1-based; 0: not started) named `stage`, `fraction` of it done;
  // `label` leads the line ("RUNNING", or empty). `now` is for tests; the estimate of the
  // time left needs a tenth of the stage and a second behind it.
  void Show(absl::string_view label, int index, int count, absl::string_view stage, double fraction,
            absl::Time now = absl::Now());
  // Ends the line with `state` ("SUCCEEDED", "done", "FAILED").
  void Finish(absl::string_view state);

  // The text after the bar: "stage 3/7 surface  45%  about 12 s left".
  static std::string StageText(int index, int count, absl::string_view stage, double fraction,
                               absl::Duration left, bool percent = true);

 private:
  std::ostream& out_;
  bool terminal_;
  int index_ = -1;
  std::string stage_;
  absl::Time stage_start_;
  absl::Time drawn_ = absl::InfinitePast();
  int tenth_ = -1;
  bool open_ = false;  // a bar is on the terminal's line
};

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_PROGRESS_LINE_H_
