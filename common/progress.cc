#include "common/progress.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "common/assert.h"

namespace sheetmesh {

Progress Progress::Sub(double begin, double end) const {
  SM_ASSERT(0.0 <= begin && begin <= end && end <= 1.0);
  Progress sub = *this;
  const double width = end_ - begin_;
  sub.begin_ = begin_ + width * begin;
  sub.end_ = begin_ + width * end;
  return sub;
}

absl::Status Progress::Update(double fraction, absl::string_view message) const {
  if (observer_ == nullptr) return absl::OkStatus();
  const double f = begin_ + (end_ - begin_) * std::clamp(fraction, 0.0, 1.0);
  if (!observer_->OnProgress(stage_, f, message)) {
    return absl::CancelledError(absl::StrCat("cancelled during stage '", stage_, "'"));
  }
  return absl::OkStatus();
}

bool DeadlineObserver::OnProgress(absl::string_view stage, double fraction,
                                  absl::string_view message) {
  if (absl::Now() > deadline_) {
    std::lock_guard<std::mutex> lock(mu_);
    if (!expired_) stage_ = std::string(stage);
    expired_ = true;
    return false;
  }
  return inner_ == nullptr || inner_->OnProgress(stage, fraction, message);
}

std::optional<std::string> DeadlineObserver::expired_in() {
  std::lock_guard<std::mutex> lock(mu_);
  return expired_ ? std::optional<std::string>(stage_) : std::nullopt;
}

}  // namespace sheetmesh
