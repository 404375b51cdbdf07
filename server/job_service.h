// JobService: create (idempotent, with the cache of identical work), get, list, cancel,
// delete, and watch as a server stream.
#ifndef SHEETMESH_SERVER_JOB_SERVICE_H_
#define SHEETMESH_SERVER_JOB_SERVICE_H_

#include <string>

#include "server/service_context.h"
#include "sheetmesh/v1/jobs.grpc.pb.h"

namespace sheetmesh::server {

// The cache key of identical work: sha256 of the pipeline version, the input's identity
// (its digest; for a path, the resolved path, size and modification time), the file name
// and the canonical parameters (runtime::ResolveJobParameters). kNotFound when a path
// vanished.
absl::StatusOr<std::string> CacheKey(const v1::CreateJobRequest& request,
                                     const std::string& resolved_path,
                                     const std::string& canonical_parameters);

class JobServiceImpl final : public v1::JobService::Service {
 public:
  explicit JobServiceImpl(const ServiceContext* ctx) : ctx_(ctx) {}

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
  grpc::Status WatchJob(grpc::ServerContext* context, const v1::WatchJobRequest* request,
                        grpc::ServerWriter<v1::WatchJobResponse>* writer) override;

 private:
  // The stored job with the running job's live progress.
  absl::StatusOr<v1::Job> Fresh(const std::string& name);

  const ServiceContext* ctx_;
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_JOB_SERVICE_H_
