#include "server/job_events.h"

namespace sheetmesh::server {

void JobEvents::Changed() {
  cv_.notify_all();
  std::function<void()> listener;
  {
    std::lock_guard<std::mutex> lock(mu_);
    listener = listener_;
  }
  if (listener) listener();
}

void JobEvents::SetListener(std::function<void()> listener) {
  std::lock_guard<std::mutex> lock(mu_);
  listener_ = std::move(listener);
}

void JobEvents::SetRelay(std::function<void(const JobEvent&)> relay) {
  std::lock_guard<std::mutex> lock(mu_);
  relay_ = std::move(relay);
}

void JobEvents::Record(const JobEvent& event, bool relay) {
  std::function<void(const JobEvent&)> relay_to;
  {
    std::lock_guard<std::mutex> lock(mu_);
    Entry& e = jobs_[event.job];
    ++e.version;
    if (event.kind == JobEvent::Kind::kStage) {
      e.stages.emplace_back(e.version, event.progress);
      if (e.stages.size() > kStagesKept) e.stages.pop_front();
    } else if (event.kind == JobEvent::Kind::kFinished) {
      finished_.push_back(event.job);
      if (finished_.size() > kFinishedKept) {
        // A watcher of a job this old finds it finished and ends: its entry can go.
        jobs_.erase(finished_.front());
        finished_.pop_front();
      }
    }
    if (relay) relay_to = relay_;
  }
  Changed();
  if (relay_to) relay_to(event);
}

void JobEvents::Apply(const JobEvent& event) { Record(event, /*relay=*/false); }

void JobEvents::Notify(const std::string& job) {
  Record({JobEvent::Kind::kChanged, job, {}}, /*relay=*/true);
}

void JobEvents::NotifyStage(const std::string& job, const v1::JobProgress& progress) {
  Record({JobEvent::Kind::kStage, job, progress}, /*relay=*/true);
}

void JobEvents::NotifyFinished(const std::string& job) {
  Record({JobEvent::Kind::kFinished, job, {}}, /*relay=*/true);
}

uint64_t JobEvents::Version(const std::string& job) {
  std::lock_guard<std::mutex> lock(mu_);
  auto it = jobs_.find(job);
  return it == jobs_.end() ? 0 : it->second.version;
}

std::vector<v1::JobProgress> JobEvents::StagesSince(const std::string& job, uint64_t seen) {
  std::lock_guard<std::mutex> lock(mu_);
  std::vector<v1::JobProgress> out;
  auto it = jobs_.find(job);
  if (it == jobs_.end()) return out;
  for (const auto& [version, progress] : it->second.stages) {
    if (version > seen) out.push_back(progress);
  }
  return out;
}

uint64_t JobEvents::Wait(const std::string& job, uint64_t seen, absl::Duration timeout) {
  std::unique_lock<std::mutex> lock(mu_);
  auto version = [&] {
    auto it = jobs_.find(job);
    return it == jobs_.end() ? uint64_t{0} : it->second.version;
  };
  cv_.wait_for(lock, absl::ToChronoMilliseconds(timeout),
               [&] { return closed_ || version() != seen; });
  return version();
}

bool JobEvents::closed() {
  std::lock_guard<std::mutex> lock(mu_);
  return closed_;
}

void JobEvents::Close() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    closed_ = true;
  }
  Changed();
}

}  // namespace sheetmesh::server
