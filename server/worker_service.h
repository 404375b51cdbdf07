// WorkerService: remote sheetmesh-worker processes lease jobs from the job store through
// any server, keep their leases, report progress and end the jobs. A server with
// --worker_token_file takes workers with that token only; an open server (no tokens)
// takes any; a server with tenant tokens and no worker token takes none.
#ifndef SHEETMESH_SERVER_WORKER_SERVICE_H_
#define SHEETMESH_SERVER_WORKER_SERVICE_H_

#include <map>
#include <mutex>
#include <string>

#include "server/service_context.h"
#include "sheetmesh/v1/workers.grpc.pb.h"

namespace sheetmesh::server {

class WorkerServiceImpl final : public v1::WorkerService::Service {
 public:
  explicit WorkerServiceImpl(ServiceContext* ctx) : ctx_(ctx) {}

  grpc::Status LeaseJob(grpc::ServerContext* context, const v1::LeaseJobRequest* request,
                        v1::LeaseJobResponse* response) override;
  grpc::Status RenewLease(grpc::ServerContext* context, const v1::RenewLeaseRequest* request,
                          v1::RenewLeaseResponse* response) override;
  grpc::Status ReportProgress(grpc::ServerContext* context,
                              const v1::ReportProgressRequest* request,
                              v1::ReportProgressResponse* response) override;
  grpc::Status FinishJob(grpc::ServerContext* context, const v1::FinishJobRequest* request,
                         v1::Job* response) override;
  grpc::Status ReleaseJob(grpc::ServerContext* context, const v1::ReleaseJobRequest* request,
                          v1::ReleaseJobResponse* response) override;
  grpc::Status SplitJob(grpc::ServerContext* context, const v1::SplitJobRequest* request,
                        v1::Job* response) override;

 private:
  grpc::Status Authorize(const grpc::ServerContext& context) const;
  // Whether the worker must stop `job`: a cancel was asked, or it no longer runs.
  bool MustStop(const std::string& job) const;

  // kInvalidArgument, kPermissionDenied or kFailedPrecondition unless `a` may become an
  // artifact of `job`: a plain file name, a blob its worker uploaded for it, stored.
  absl::Status CheckArtifact(const v1::Artifact& a, const std::string& job) const;
  // The job a brick task belongs to ("" for another job), remembered while it runs.
  std::string ParentOf(const std::string& job);

  ServiceContext* ctx_;
  std::mutex mu_;
  std::map<std::string, int> stage_;           // job -> the last stage told to watchers
  std::map<std::string, std::string> parent_;  // job -> its parent ("" for none)
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_WORKER_SERVICE_H_
