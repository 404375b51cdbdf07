// JobService: create (idempotent, with the cache of identical work), get, list, cancel,
// delete, and watch as a server stream, each within the caller's tenant: another tenant's
// job is, to this one, a job that does not exist.
#ifndef SHEETMESH_SERVER_JOB_SERVICE_H_
#define SHEETMESH_SERVER_JOB_SERVICE_H_

#include <memory>
#include <string>

#include "server/job_view.h"
#include "server/service_context.h"
#include "sheetmesh/v1/jobs.grpc.pb.h"

namespace sheetmesh::server {

class WatchHub;

// The cache key of identical work: sha256 of the pipeline version, the tenant, the input's
// identity (its digest; for a path, the resolved path, size and modification time), the
// file name and the canonical parameters (runtime::ResolveJobParameters). kNotFound when a
// path vanished.
absl::StatusOr<std::string> CacheKey(const std::string& tenant, const v1::CreateJobRequest& request,
                                     const std::string& resolved_path,
                                     const std::string& canonical_parameters);

// WatchJob runs on gRPC's callback API (a watch costs no thread while it waits); the rest
// are synchronous handlers.
class JobServiceImpl final
    : public v1::JobService::WithCallbackMethod_WatchJob<v1::JobService::Service> {
 public:
  explicit JobServiceImpl(const ServiceContext* ctx);
  ~JobServiceImpl() override;

  grpc::Status CreateJob(grpc::ServerContext* context, const v1::CreateJobRequest* request,
                         v1::Job* response) override;
  grpc::Status GetJob(grpc::ServerContext* context, const v1::GetJobRequest* request,
                      v1::Job* response) override;
  grpc::Status ListJobs(grpc::ServerContext* context, const v1::ListJobsRequest* request,
                        v1::ListJobsResponse* response) override;
  grpc::Status CancelJob(grpc::ServerContext* context, const v1::CancelJobRequest* request,
                         v1::Job* response) override;
  grpc::Status DeleteJob(grpc::ServerContext* context, const v1::DeleteJobRequest* request,
                         v1::DeleteJobResponse* response) override;
  grpc::ServerWriteReactor<v1::WatchJobResponse>* WatchJob(
      grpc::CallbackServerContext* context, const v1::WatchJobRequest* request) override;

  // Ends the watches (UNAVAILABLE: the server is stopping) and stops their helper thread.
  void StopWatches();

 private:
  absl::Status CheckInput(const std::string& tenant, const v1::JobInput& in,
                          std::string* resolved_path);
  // Whether `digest` is stored and, unless tenants are open, this tenant's.
  absl::StatusOr<bool> Usable(const std::string& tenant, const v1::Digest& digest);

  const ServiceContext* ctx_;
  std::unique_ptr<WatchHub> hub_;
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_JOB_SERVICE_H_
