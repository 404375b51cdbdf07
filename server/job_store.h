// JobStore: where accepted jobs live, durably. A job accepted is never lost: it is written
// before CreateJob answers, and a job whose worker vanished (lease expired, server killed)
// goes back to the queue until it has been tried max_attempts times.
#ifndef SHEETMESH_SERVER_JOB_STORE_H_
#define SHEETMESH_SERVER_JOB_STORE_H_

#include <cstdint>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "sheetmesh/v1/jobs.pb.h"

namespace sheetmesh::server {

// Jobs belong to tenants (Job.tenant): request ids are unique within a tenant, and List
// lists one tenant's jobs. A tenant owns the blobs it uploaded and those its jobs name (as
// input or artifact); GetJob and the blob service check ownership.
//
// Implementations are thread-safe.
class JobStore {
 public:
  virtual ~JobStore() = default;

  // Stores a new QUEUED job (or, for a `job` already SUCCEEDED from a cache, that). When a
  // job of the same tenant with the same request_id exists, returns it and sets *created
  // to false.
  virtual absl::StatusOr<v1::Job> Create(v1::Job job, const std::string& cache_key,
                                         bool* created) = 0;
  // kNotFound naming the job.
  virtual absl::StatusOr<v1::Job> Get(const std::string& name) = 0;
  // The job of `tenant` created with `request_id`, if any.
  virtual absl::StatusOr<std::optional<v1::Job>> FindByRequestId(const std::string& tenant,
                                                                 const std::string& request_id) = 0;
  // The jobs of `tenant` (not brick tasks), newest first; page_token is opaque ("" = first page).
  // Sets *next_token ("" = last).
  virtual absl::StatusOr<std::vector<v1::Job>> List(const std::string& tenant, v1::JobState state,
                                                    int page_size, const std::string& page_token,
                                                    std::string* next_token) = 0;
  // The oldest QUEUED job (a split job only once its tasks have all ended), now RUNNING under
  // `worker` until now + lease; attempts + 1.
  virtual absl::StatusOr<std::optional<v1::Job>> LeaseNext(const std::string& worker,
                                                           absl::Duration lease) = 0;
  // kFailedPrecondition when the job is not RUNNING under `worker`.
  virtual absl::Status Renew(const std::string& name, const std::string& worker,
                             absl::Duration lease) = 0;
  // Stores the job's progress (RUNNING under `worker` only).
  virtual absl::Status SetProgress(const std::string& name, const std::string& worker,
                                   const v1::JobProgress& progress) = 0;
  // Ends a RUNNING job of `worker` in `state` (SUCCEEDED, FAILED or CANCELLED).
  virtual absl::StatusOr<v1::Job> Finish(const std::string& name, const std::string& worker,
                                         v1::JobState state, const v1::JobError& error,
                                         const std::vector<v1::Artifact>& artifacts) = 0;
  // Puts a RUNNING job of `worker` back in the queue, its attempt not counted.
  virtual absl::Status Release(const std::string& name, const std::string& worker) = 0;
  // Splits a job run as bricks, RUNNING under `worker`, into `count` brick tasks
  // (BrickTasks): stores them QUEUED, records the plan and their names in the job's bricks, and
  // puts the job back in the queue (its attempt not counted), where LeaseNext passes it by until
  // every task has ended. kFailedPrecondition when the job is not RUNNING under `worker`,
  // or is split already; kInvalidArgument for a count outside [1, kMaxBricks].
  virtual absl::StatusOr<v1::Job> Split(const std::string& name, const std::string& worker,
                                        const v1::Artifact& plan, int count) = 0;
  // The brick tasks of a split job, in the plan's order (none for another job).
  virtual absl::StatusOr<std::vector<v1::Job>> Tasks(const std::string& name) = 0;
  // QUEUED: CANCELLED now. RUNNING: marked, the worker stops it. Finished: unchanged.
  virtual absl::StatusOr<v1::Job> RequestCancel(const std::string& name) = 0;
  virtual absl::StatusOr<bool> CancelRequested(const std::string& name) = 0;
  // Cancels the brick tasks of the split job `name` at once (one transaction, not one per
  // task): QUEUED ones CANCELLED now, RUNNING ones marked for their workers. Returns how
  // many it touched; 0 for a job that is not split.
  virtual absl::StatusOr<int> CancelTasks(const std::string& name) = 0;
  // kFailedPrecondition unless the job has finished. A split job's tasks go with it.
  virtual absl::Status Delete(const std::string& name) = 0;
  // RUNNING jobs whose lease ended go back to QUEUED, or FAILED after max_attempts.
  // `all` treats every RUNNING job as expired (a restart: no worker of the old process
  // lives). With `not_the_jobs_fault` (the server that ran them died, and its jobs ran
  // isolated, so none of them took it down) the lost run is not counted as an attempt.
  // Returns how many were requeued or ended; `ended` (when given) receives those that ended
  // (FAILED or CANCELLED) as stored, so that the caller can act on them (a brick task's
  // siblings, its job's watchers).
  virtual absl::StatusOr<int> RequeueExpired(int max_attempts, bool all,
                                             bool not_the_jobs_fault = false,
                                             std::vector<v1::Job>* ended = nullptr) = 0;
  // A SUCCEEDED job with this cache key.
  virtual absl::StatusOr<std::optional<v1::Job>> FindCached(const std::string& cache_key) = 0;
  // The jobs in `state`, brick tasks not counted (a job's bricks are one job's work).
  virtual absl::StatusOr<int64_t> CountInState(v1::JobState state) = 0;
  // The QUEUED brick tasks of every job: the work the queue holds beside its jobs.
  virtual absl::StatusOr<int64_t> CountQueuedTasks() = 0;

  // Records that `tenant` uploaded the blob `hash`.
  virtual absl::Status AddUploadedBlob(const std::string& tenant, const std::string& hash) = 0;
  // Whether `tenant` uploaded the blob or has a job that names it.
  virtual absl::StatusOr<bool> OwnsBlob(const std::string& tenant, const std::string& hash) = 0;
  // The blobs some job names (input or artifact), whatever its tenant or state.
  virtual absl::StatusOr<std::set<std::string>> ReferencedBlobs() = 0;
  // The blob was collected: nobody owns it any more.
  virtual absl::Status ForgetBlob(const std::string& hash) = 0;
};

// SQLite in WAL mode at `path`.
absl::StatusOr<std::unique_ptr<JobStore>> OpenSqliteJobStore(const std::string& path);

// PostgreSQL named by a libpq connection string ("host=db port=5432 dbname=sheetmesh
// user=sheetmesh", or a postgresql:// URI), for several servers over one database; the
// tables are made when missing. kUnavailable naming the address when it cannot connect;
// later calls answer kUnavailable while the database is gone and work again when it is back.
absl::StatusOr<std::unique_ptr<JobStore>> OpenPostgresJobStore(const std::string& conninfo);

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_JOB_STORE_H_
