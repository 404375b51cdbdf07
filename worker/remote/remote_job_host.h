// RemoteJobHost: the JobHost of sheetmesh-worker — jobs leased from a sheetmesh-server
// over gRPC (WorkerService), inputs downloaded from its blob store (or read from shared
// storage under the worker's allowed roots), artifacts uploaded to it.
#ifndef SHEETMESH_WORKER_REMOTE_REMOTE_JOB_HOST_H_
#define SHEETMESH_WORKER_REMOTE_REMOTE_JOB_HOST_H_

#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "client/client.h"
#include "sheetmesh/v1/workers.grpc.pb.h"
#include "worker/remote/blob_cache.h"
#include "worker/runtime/job_host.h"

namespace sheetmesh::remote {

struct RemoteJobHostOptions {
  client::ClientOptions server;            // address, worker token, TLS
  std::string scratch_dir;                 // downloaded inputs go here
  std::vector<std::string> allowed_roots;  // paths jobs may name (shared storage)
  absl::Duration progress_interval = absl::Milliseconds(500);  // at most this often
  absl::Duration lease_poll = absl::Seconds(1);  // between LeaseJob calls with none queued
};

class RemoteJobHost : public runtime::JobHost {
 public:
  static absl::StatusOr<std::unique_ptr<RemoteJobHost>> Connect(RemoteJobHostOptions options);

  absl::StatusOr<std::optional<v1::Job>> Lease(const std::string& worker,
                                               absl::Duration wait) override;
  absl::Status Renew(const std::string& job, const std::string& worker) override;
  bool ReportProgress(const std::string& job, const std::string& worker,
                      const runtime::ProgressUpdate& update) override;
  // An uploaded volume is kept in SCRATCH/cache under its digest for the next task of it;
  // with `only`, those bytes of it are fetched into a file as large as the volume, and
  // kept with the list of what it holds, for the next brick.
  absl::StatusOr<runtime::LocalVolume> ResolveInput(
      const v1::Job& job, const std::vector<runtime::ByteRange>* only) override;
  absl::StatusOr<v1::Artifact> PutArtifact(const std::string& job, const std::string& worker,
                                           const std::string& path,
                                           const std::string& media_type) override;
  absl::Status Finish(const std::string& job, const std::string& worker, const absl::Status& result,
                      const std::vector<v1::Artifact>& artifacts) override;
  absl::Status Release(const std::string& job, const std::string& worker) override;
  absl::Status Split(const std::string& job, const std::string& worker, const v1::Artifact& plan,
                     int count) override;
  absl::Status FetchBlob(const v1::Digest& digest, const std::string& path) override;

  // Wakes a Lease waiting for work (drain).
  void Stop();

 private:
  explicit RemoteJobHost(RemoteJobHostOptions o) : options_(std::move(o)) {}
  std::unique_ptr<grpc::ClientContext> Context() const { return client_->Context(); }
  std::string InputDir(const std::string& job) const;
  // A job ended here: its progress state and downloaded input go.
  void Forget(const std::string& job);

  RemoteJobHostOptions options_;
  std::unique_ptr<client::SheetmeshClient> client_;  // for its channel and token
  std::unique_ptr<v1::WorkerService::Stub> workers_;
  std::mutex mu_;
  std::condition_variable stop_cv_;
  bool stopping_ = false;
  struct Live {
    absl::Time reported;
    int stage = 0;
  };
  std::map<std::string, Live> live_;

  // Uploaded volumes, fetched once (whole, or a brick's bytes) into scratch_dir/cache and
  // linked into each job's input folder.
  std::unique_ptr<BlobCache> cache_;
};

}  // namespace sheetmesh::remote

#endif  // SHEETMESH_WORKER_REMOTE_REMOTE_JOB_HOST_H_
