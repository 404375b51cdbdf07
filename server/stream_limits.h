// StreamLimits: how many streams of one kind (uploads, watches) are open, per client and in
// all, against two limits. A stream past a limit is refused with RESOURCE_EXHAUSTED naming
// the limit and the flag that sets it, so that one client cannot take every descriptor,
// thread or slot of the server.
#ifndef SHEETMESH_SERVER_STREAM_LIMITS_H_
#define SHEETMESH_SERVER_STREAM_LIMITS_H_

#include <map>
#include <mutex>
#include <string>

#include "absl/status/statusor.h"

namespace sheetmesh::server {

// Thread-safe.
class StreamLimits {
 public:
  // `kind` ("upload", "watch") and `flag` (the flags' common stem, e.g. "max_watch_streams":
  // --max_watch_streams and --max_watch_streams_per_client) name the limit in messages.
  StreamLimits(std::string kind, std::string flag, int per_client, int total)
      : kind_(std::move(kind)), flag_(std::move(flag)), per_client_(per_client), total_(total) {}
  StreamLimits(const StreamLimits&) = delete;
  StreamLimits& operator=(const StreamLimits&) = delete;

  // One open stream; closing it (destruction or Release) frees its place.
  class Slot {
   public:
    Slot() = default;
    Slot(Slot&& o) noexcept : owner_(o.owner_), client_(std::move(o.client_)) {
      o.owner_ = nullptr;
    }
    Slot& operator=(Slot&& o) noexcept;
    ~Slot() { Release(); }
    void Release();

   private:
    friend class StreamLimits;
    Slot(StreamLimits* owner, std::string client) : owner_(owner), client_(std::move(client)) {}
    StreamLimits* owner_ = nullptr;
    std::string client_;
  };

  // A place for one more stream of `client`; kResourceExhausted past either limit.
  absl::StatusOr<Slot> Acquire(const std::string& client);
  int open() const;
  int open_of(const std::string& client) const;

 private:
  void Free(const std::string& client);

  const std::string kind_, flag_;
  const int per_client_, total_;
  mutable std::mutex mu_;
  std::map<std::string, int> open_;
  int total_open_ = 0;
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_STREAM_LIMITS_H_
