// What the gRPC services share: the stores, the worker host, and the server's settings.
#ifndef SHEETMESH_SERVER_SERVICE_CONTEXT_H_
#define SHEETMESH_SERVER_SERVICE_CONTEXT_H_

#include <string>
#include <vector>

#include "absl/time/time.h"
#include "server/auth.h"
#include "server/blob_store.h"
#include "server/job_events.h"
#include "server/job_store.h"
#include "server/local_job_host.h"
#include "server/stream_limits.h"
#include "worker/runtime/job_process.h"

namespace sheetmesh::server {

struct ServiceLimits {
  int64_t max_blob_bytes = int64_t{64} << 30;  // an upload beyond this is refused
  // A tenant's unfinished uploads (bytes not yet stored as blobs) may not pass this: a
  // client that opens uploads and never finishes them fills no disk.
  int64_t max_unfinished_upload_bytes_per_tenant = int64_t{64} << 30;
  int64_t max_queued_jobs = 1000;  // CreateJob beyond this (jobs and brick tasks) is refused
  int max_brick_tasks = 512;       // a job's plan of more bricks fails the job
  // Open Write streams (each holds two descriptors and a thread while it lasts).
  int max_upload_streams = 256;
  int max_upload_streams_per_client = 64;
  // Open WatchJob streams (cheap: no thread each, but memory and a timer).
  int max_watch_streams = 2048;
  int max_watch_streams_per_client = 256;
  // A Write stream that brings no byte for this long is closed (its descriptors freed);
  // its upload stays for resumption until nobody has written it for upload_expiry.
  absl::Duration upload_idle_timeout = absl::Minutes(2);
  absl::Duration upload_expiry = absl::Hours(24);
};

// How InspectVolume opens a volume: in a child with a job's memory limit (a header can
// claim any size, and a reader that believed one would take the server with it), or here.
struct InspectOptions {
  bool isolate = true;
  std::string program;      // the child's program ("": this one)
  std::string scratch_dir;  // the child's folder is made here
  runtime::JobLimits limits;
};

struct ServiceContext {
  JobStore* jobs = nullptr;
  BlobStore* blobs = nullptr;
  JobEvents* events = nullptr;
  LocalJobHost* host = nullptr;
  std::vector<std::string> allowed_roots;
  const Tenants* tenants = nullptr;  // who may call, and their tenants
  ServiceLimits limits;
  StreamLimits* upload_streams = nullptr;
  StreamLimits* watch_streams = nullptr;
  absl::Duration heartbeat = absl::Seconds(5);      // WatchJob sends at least this often
  absl::Duration worker_lease = absl::Seconds(30);  // a remote worker's lease
  bool cache = true;                                // reuse results of identical work
  InspectOptions inspect;
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_SERVICE_CONTEXT_H_
