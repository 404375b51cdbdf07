// Server: the embedded default — one process with the gRPC services, a SQLite job store,
// a filesystem blob store under one data folder, and an in-process worker pool.
#ifndef SHEETMESH_SERVER_SERVER_H_
#define SHEETMESH_SERVER_SERVER_H_

#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "server/service_context.h"

namespace grpc {
class Server;
}

#include "worker/runtime/job_process.h"

namespace sheetmesh::server {

struct ServerOptions {
  std::string address = "127.0.0.1:50051";  // host:port; port 0 picks a free one
  std::string data_dir;                     // jobs.db, blobs, scratch (required)
  int workers = 0;                          // in-process workers (0: the number of cores)
  std::vector<std::string> allowed_roots;   // paths jobs may name (none: only uploads)
  std::string tls_cert;                     // PEM files; both empty: no TLS
  std::string tls_key;
  std::string auth_token;  // required bearer token ("" = none)
  ServiceLimits limits;
  absl::Duration lease = absl::Seconds(30);     // worker lease; renewed every third
  int max_attempts = 3;                         // runs before a job whose workers keep
                                                // vanishing is FAILED
  absl::Duration heartbeat = absl::Seconds(5);  // WatchJob heartbeat
  bool cache = true;                            // reuse results of identical work
  int max_message_bytes = 4 << 20;              // gRPC message limit (pieces are 1 MiB)
  // Each job runs in a child process of `job_program` (""; this program, which must call
  // runtime::RunJobChildIfAsked in main) with these limits; false: in a worker thread.
  bool isolate_jobs = true;
  std::string job_program;
  runtime::JobLimits job_limits;
};

// Thread-safe.
class Server {
 public:
  // Opens the stores (requeueing the jobs of a previous process), starts the services and
  // the workers. kInvalidArgument for a bad option, kUnavailable when the address cannot
  // be bound.
  static absl::StatusOr<std::unique_ptr<Server>> Start(const ServerOptions& options);
  ~Server();

  // The bound port.
  int port() const { return port_; }
  // Graceful shutdown: stop accepting jobs for workers, let running jobs finish for up to
  // `drain`, give the rest back to the queue (they run again at the next start), then
  // stop the RPCs (waiting at most a few seconds for open calls).
  void Shutdown(absl::Duration drain);
  // Blocks until Shutdown() has completed.
  void Wait();

 private:
  Server() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int port_ = 0;
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_SERVER_H_
