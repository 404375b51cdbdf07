// Progress reporting and cancellation for long pipeline operations, in the spirit of
// OpenVDB's util::NullInterrupter: operations report fractions and stop when asked.
#ifndef SHEETMESH_COMMON_PROGRESS_H_
#define SHEETMESH_COMMON_PROGRESS_H_

#include <mutex>
#include <optional>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"

namespace sheetmesh {

// Receives progress of the pipeline. Implementations must be thread-safe: operations
// that run on several threads may report from any of them.
class ProgressObserver {
 public:
  virtual ~ProgressObserver() = default;

  // `stage` names the running step ("scvd"), `fraction` in [0, 1] is how far that step is,
  // `message` is an optional detail. Returns false to ask the operation to stop; it then
  // returns kCancelled promptly.
  virtual bool OnProgress(absl::string_view stage, double fraction, absl::string_view message) = 0;
};

// A cheap, copyable handle passed to long operations. A default-constructed Progress
// reports nowhere and is never cancelled. A handle covers a sub-range [begin, end] of its
// stage, so that a step can hand a part of its range to a sub-step.
class Progress {
 public:
  Progress() = default;
  Progress(ProgressObserver* observer, std::string stage)
      : observer_(observer), stage_(std::move(stage)) {}

  // A handle for a new stage of the same observer, covering [0, 1] of that stage.
  Progress Stage(std::string stage) const { return Progress(observer_, std::move(stage)); }

  // This handle's stage and range, reported to `observer` instead (one that wraps this
  // handle's observer: a deadline, a stage clock).
  Progress WithObserver(ProgressObserver* observer) const {
    Progress p = *this;
    p.observer_ = observer;
    return p;
  }

  // A handle whose [0, 1] maps onto [begin, end] of this handle's range.
  // REQUIRES: 0 <= begin <= end <= 1.
  Progress Sub(double begin, double end) const;

  // Reports `fraction` in [0, 1] of this handle's range. Returns kCancelled (naming the
  // stage) if the observer asks to stop, OK otherwise.
  absl::Status Update(double fraction, absl::string_view message = {}) const;

  // Update() at most once every `stride` calls: for inner loops. `counter` is the caller's
  // loop counter; `total` its end (for the fraction).
  absl::Status Tick(int64_t counter, int64_t total, int64_t stride = 1 << 16) const {
    if (observer_ == nullptr || counter % stride != 0) return absl::OkStatus();
    return Update(total > 0 ? static_cast<double>(counter) / total : 0.0);
  }

  bool enabled() const { return observer_ != nullptr; }
  ProgressObserver* observer() const { return observer_; }
  const std::string& stage() const { return stage_; }

 private:
  ProgressObserver* observer_ = nullptr;  // not owned
  std::string stage_;
  double begin_ = 0.0;
  double end_ = 1.0;
};

// Ends work past a deadline: every report after it asks to stop (the work returns
// kCancelled), and expired_in() says in which stage that was, so that the caller can say
// kDeadlineExceeded rather than cancelled. Reports before it go to `inner` (may be null).
// Thread-safe.
class DeadlineObserver : public ProgressObserver {
 public:
  DeadlineObserver(ProgressObserver* inner, absl::Time deadline)
      : inner_(inner), deadline_(deadline) {}
  bool OnProgress(absl::string_view stage, double fraction, absl::string_view message) override;
  // The stage the deadline passed in, or nullopt while it has not.
  std::optional<std::string> expired_in();
  absl::Time deadline() const { return deadline_; }

 private:
  ProgressObserver* inner_;
  const absl::Time deadline_;
  std::mutex mu_;
  bool expired_ = false;
  std::string stage_;
};

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_PROGRESS_H_
