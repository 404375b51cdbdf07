// LocalJobHost: the job host of the embedded server's in-process worker pool — jobs from
// the JobStore, inputs and outputs in the BlobStore, progress kept in memory (and stored
// at each stage), changes announced to watchers.
#ifndef SHEETMESH_SERVER_LOCAL_JOB_HOST_H_
#define SHEETMESH_SERVER_LOCAL_JOB_HOST_H_

#include <condition_variable>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "absl/time/time.h"
#include "server/blob_store.h"
#include "server/bricked_jobs.h"
#include "server/job_events.h"
#include "server/job_store.h"
#include "worker/runtime/job_host.h"

namespace sheetmesh::server {

struct LocalJobHostOptions {
  std::vector<std::string> allowed_roots;                     // for volume_path inputs
  std::string scratch_dir;                                    // per-job links to uploaded volumes
  absl::Duration lease = absl::Seconds(30);                   // lease length
  absl::Duration progress_store_interval = absl::Seconds(2);  // store progress this often
  // Look this often whether the store says stop (a cancel asked of another server over the
  // same database, or the lease lost).
  absl::Duration cancel_poll_interval = absl::Seconds(1);
  SplitLimits split;  // what one job's bricks may be
};

// Thread-safe.
class LocalJobHost : public runtime::JobHost {
 public:
  LocalJobHost(JobStore* store, BlobStore* blobs, JobEvents* events, LocalJobHostOptions options);

  absl::StatusOr<std::optional<v1::Job>> Lease(const std::string& worker,
                                               absl::Duration wait) override;
  absl::Status Renew(const std::string& job, const std::string& worker) override;
  bool ReportProgress(const std::string& job, const std::string& worker,
                      const runtime::ProgressUpdate& update) override;
  // The volume lies here whole: `only` changes nothing.
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

  // Wakes workers waiting in Lease (a job was queued).
  void WakeWorkers();
  // The running job stops at its next progress report.
  void MarkCancelled(const std::string& job);
  // The latest progress of a running job, fresher than the stored one.
  std::optional<v1::JobProgress> Progress(const std::string& job);

 private:
  struct Live {
    v1::JobProgress progress;
    absl::Time stored;    // when progress was last stored
    absl::Time notified;  // when watchers were last told
    double notified_fraction = -1;
    absl::Time cancel_checked;  // when the store was last asked whether to stop
    std::string parent;         // of a brick task: its job, whose watchers hear of it too
  };

  // Removes the links to a job's uploaded input.
  void RemoveInputs(const std::string& job);

  JobStore* store_;
  BlobStore* blobs_;
  JobEvents* events_;
  LocalJobHostOptions options_;
  std::mutex mu_;
  std::condition_variable work_;
  uint64_t wake_ = 0;
  std::set<std::string> cancelled_;
  std::map<std::string, Live> live_;
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_LOCAL_JOB_HOST_H_
