// BlobService: uploads (resumable), find-missing and ranged reads over the BlobStore, each
// within the caller's tenant. A helper thread closes Write streams that stall (past
// upload_idle_timeout) and removes uploads nobody resumed (past upload_expiry).
#ifndef SHEETMESH_SERVER_BLOB_SERVICE_H_
#define SHEETMESH_SERVER_BLOB_SERVICE_H_

#include <condition_variable>
#include <map>
#include <mutex>
#include <thread>

#include "server/service_context.h"
#include "sheetmesh/v1/blobs.grpc.pb.h"

namespace sheetmesh::server {

// Metadata a remote worker sends with the uploads of a job's artifacts: the job (jobs/ID)
// and the worker holding it. Such uploads belong to the job (ArtifactOwner), so that
// FinishJob takes as artifacts only blobs uploaded for that job by its worker.
inline constexpr char kArtifactJobHeader[] = "sheetmesh-job";
inline constexpr char kArtifactWorkerHeader[] = "sheetmesh-worker";
// The owner the blob store records a job's artifact uploads under ("@job.ID").
std::string ArtifactOwner(const std::string& job);

class BlobServiceImpl final : public v1::BlobService::Service {
 public:
  explicit BlobServiceImpl(const ServiceContext* ctx);
  ~BlobServiceImpl() override;

  grpc::Status FindMissingBlobs(grpc::ServerContext* context,
                                const v1::FindMissingBlobsRequest* request,
                                v1::FindMissingBlobsResponse* response) override;
  grpc::Status Write(grpc::ServerContext* context, grpc::ServerReader<v1::WriteRequest>* reader,
                     v1::WriteResponse* response) override;
  grpc::Status QueryWriteStatus(grpc::ServerContext* context,
                                const v1::QueryWriteStatusRequest* request,
                                v1::QueryWriteStatusResponse* response) override;
  grpc::Status Read(grpc::ServerContext* context, const v1::ReadRequest* request,
                    grpc::ServerWriter<v1::ReadResponse>* writer) override;

  // Write streams the idle timeout has closed, since the start.
  int64_t idle_closed() const;

 private:
  class ActiveWrite;
  void Reap();
  // Whether `tenant` may use the blob (it owns it); a server without tokens has one tenant,
  // which owns everything stored.
  absl::StatusOr<bool> Owns(const std::string& tenant, const v1::Digest& digest) const;
  // Who the call is, for ownership: the caller's tenant, or for a worker uploading a job's
  // artifacts the job (after checking the worker holds it).
  grpc::Status Caller(grpc::ServerContext* context, std::string* owner) const;

  const ServiceContext* ctx_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::map<grpc::ServerContext*, absl::Time> writes_;  // open Write streams, last progress
  int64_t idle_closed_ = 0;
  bool stopping_ = false;
  std::thread reaper_;
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_BLOB_SERVICE_H_
