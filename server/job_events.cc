#include "server/job_events.h"

namespace sheetmesh::server {

void JobEvents::Notify(const std::string& job) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    ++versions_[job];
  }
  cv_.notify_all();
}

uint64_t JobEvents::Version(const std::string& job) {
  std::lock_guard<std::mutex> lock(mu_);
  return versions_[job];
}

uint64_t JobEvents::Wait(const std::string& job, uint64_t seen, absl::Duration timeout) {
  std::unique_lock<std::mutex> lock(mu_);
  cv_.wait_for(lock, absl::ToChronoMilliseconds(timeout),
               [&] { return closed_ || versions_[job] > seen; });
  return versions_[job];
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
  cv_.notify_all();
}

}  // namespace sheetmesh::server
