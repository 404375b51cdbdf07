// WatchJob on gRPC's callback API. A watch is a reactor that, between messages, waits in the
// hub: one thread wakes the watches whose job changed (JobEvents) or whose heartbeat is due,
// so a thousand watches cost a thousand small objects, not a thousand threads. Each watch
// holds a place in the watch stream limits (per client and in all).
#ifndef SHEETMESH_SERVER_WATCH_JOB_H_
#define SHEETMESH_SERVER_WATCH_JOB_H_

#include <grpcpp/support/server_callback.h>

#include <condition_variable>
#include <mutex>
#include <set>
#include <thread>

#include "server/service_context.h"
#include "sheetmesh/v1/jobs.pb.h"

namespace grpc {
class CallbackServerContext;
}

namespace sheetmesh::server {

// Thread-safe.
class WatchHub {
 public:
  explicit WatchHub(const ServiceContext* ctx);
  ~WatchHub();
  WatchHub(const WatchHub&) = delete;
  WatchHub& operator=(const WatchHub&) = delete;

  // A new watch (the reactor gRPC drives; it deletes itself when done).
  grpc::ServerWriteReactor<v1::WatchJobResponse>* Watch(grpc::CallbackServerContext* context,
                                                        const v1::WatchJobRequest& request);
  // Ends every watch, now and from now on, with UNAVAILABLE (the server is stopping).
  void Stop();
  // Watches waiting for a change.
  int waiting() const;

 private:
  class Reactor;
  // The hub takes `r` until its job changes or its deadline passes.
  void Wait(Reactor* r);
  // Takes `r` back from the hub; false when the hub was not holding it.
  bool Take(Reactor* r);
  void Run();

  const ServiceContext* ctx_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::set<Reactor*> waiting_;
  bool dirty_ = false;  // some job changed since the last look
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_WATCH_JOB_H_
