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

#include "worker/runtime/job_process.h"  // runtime::JobLimits

namespace sheetmesh::server {

struct ServerOptions {
  std::string address = "127.0.0.1:50051";  // host:port; port 0 picks a free one
  std::string data_dir;                     // jobs.db, blobs, scratch (required)
  // A libpq connection string: the jobs in PostgreSQL, shared by several servers over one
  // database (and one blob folder), instead of data_dir/jobs.db.
  std::string postgres;
  // The workers' scratch (default data_dir/scratch), emptied at start: each server its own
  // when several share a data folder.
  std::string scratch_dir;
  int workers = 0;            // in-process workers (0: the number of cores)
  bool local_workers = true;  // false: none here; remote sheetmesh-workers run the jobs
  std::vector<std::string> allowed_roots;  // paths jobs may name (none: only uploads)
  std::string tls_cert;                    // PEM files; both empty: no TLS
  std::string tls_key;
  // Who may call: one bearer token (of the tenant "default"), or a token file with one
  // "TOKEN [TENANT]" per line (server/auth.h). Neither: an open server.
  std::string auth_token;
  std::string auth_token_file;
  // A file holding the token remote workers (sheetmesh-worker) present.
  std::string worker_token_file;
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
  // Retention (server/retention.h): unreferenced blobs unused this long are removed, in a
  // pass at start and every gc_interval; zero keeps everything. A dry run only lists.
  absl::Duration blob_retention = absl::Hours(24 * 7);
  absl::Duration gc_interval = absl::Hours(1);
  bool gc_dry_run = false;
  // Uploads are refused (RESOURCE_EXHAUSTED) where they would leave less free space than
  // this in the data folder's file system, so that the job store and the jobs' outputs
  // always have room; health says NOT_SERVING below it, or while the process holds more
  // than nine tenths of its descriptor limit.
  int64_t min_free_disk_bytes = int64_t{256} << 20;
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

  // Why health says NOT_SERVING ("" while serving), as of the last check.
  std::string not_serving_reason() const;
  // Runs one retention pass now (also what the periodic pass does).
  absl::StatusOr<std::string> CollectNow();

 private:
  Server() = default;
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int port_ = 0;
};

// One retention pass over the data folder of `options` without serving (sheetmesh-server
// --gc_once): the listing of what was (or, dry run, would be) removed.
absl::StatusOr<std::string> CollectOnce(const ServerOptions& options);

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_SERVER_H_
