// What the gRPC services share: the stores, the worker host, and the server's settings.
#ifndef SHEETMESH_SERVER_SERVICE_CONTEXT_H_
#define SHEETMESH_SERVER_SERVICE_CONTEXT_H_

#include <grpcpp/server_context.h>

#include <string>
#include <vector>

#include "absl/time/time.h"
#include "server/blob_store.h"
#include "server/job_events.h"
#include "server/job_store.h"
#include "server/local_job_host.h"

namespace sheetmesh::server {

struct ServiceLimits {
  int64_t max_blob_bytes = int64_t{64} << 30;  // an upload beyond this is refused
  int64_t max_queued_jobs = 1000;              // CreateJob beyond this is refused
};

struct ServiceContext {
  JobStore* jobs = nullptr;
  BlobStore* blobs = nullptr;
  JobEvents* events = nullptr;
  LocalJobHost* host = nullptr;
  std::vector<std::string> allowed_roots;
  std::string auth_token;  // "" = no authentication
  ServiceLimits limits;
  absl::Duration heartbeat = absl::Seconds(5);  // WatchJob sends at least this often
  bool cache = true;                            // reuse results of identical work
};

// UNAUTHENTICATED unless the call carries "authorization: Bearer <token>" (when a token
// is configured).
grpc::Status CheckAuth(const grpc::ServerContext* context, const std::string& token);

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_SERVICE_CONTEXT_H_
