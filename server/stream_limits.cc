#include "server/stream_limits.h"

#include "absl/strings/str_cat.h"

namespace sheetmesh::server {

StreamLimits::Slot& StreamLimits::Slot::operator=(Slot&& o) noexcept {
  if (this != &o) {
    Release();
    owner_ = o.owner_;
    client_ = std::move(o.client_);
    o.owner_ = nullptr;
  }
  return *this;
}

void StreamLimits::Slot::Release() {
  if (owner_ != nullptr) owner_->Free(client_);
  owner_ = nullptr;
}

absl::StatusOr<StreamLimits::Slot> StreamLimits::Acquire(const std::string& client) {
  std::lock_guard<std::mutex> lock(mu_);
  int& mine = open_[client];
  if (mine >= per_client_) {
    if (mine == 0) open_.erase(client);
    return absl::ResourceExhaustedError(
        absl::StrCat("too many open ", kind_, " streams: ", client, " has ", mine,
                     " open, the limit per client (--", flag_,
                     "_per_client); close one or wait for one to end"));
  }
  if (total_open_ >= total_) {
    if (mine == 0) open_.erase(client);
    return absl::ResourceExhaustedError(
        absl::StrCat("too many open ", kind_, " streams: the server has ", total_open_,
                     " open, its limit (--", flag_, "); try again later"));
  }
  ++mine;
  ++total_open_;
  return Slot(this, client);
}

void StreamLimits::Free(const std::string& client) {
  std::lock_guard<std::mutex> lock(mu_);
  auto it = open_.find(client);
  if (it == open_.end()) return;
  if (--it->second <= 0) open_.erase(it);
  --total_open_;
}

int StreamLimits::open() const {
  std::lock_guard<std::mutex> lock(mu_);
  return total_open_;
}

int StreamLimits::open_of(const std::string& client) const {
  std::lock_guard<std::mutex> lock(mu_);
  auto it = open_.find(client);
  return it == open_.end() ? 0 : it->second;
}

}  // namespace sheetmesh::server
