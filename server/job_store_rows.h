// What every JobStore shares: job ids and names, the request-id key of a tenant, the blobs
// a job names, parsing a stored record, and what becomes of a job whose worker was lost.
#ifndef SHEETMESH_SERVER_JOB_STORE_ROWS_H_
#define SHEETMESH_SERVER_JOB_STORE_ROWS_H_

#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "google/protobuf/timestamp.pb.h"
#include "sheetmesh/v1/jobs.pb.h"
#include "worker/runtime/job_host.h"

namespace sheetmesh::server {

inline constexpr const char* kDefaultTenant = "default";

// `t` (now, by default) as a protobuf timestamp, to the millisecond.
google::protobuf::Timestamp TimestampOf(absl::Time t);
google::protobuf::Timestamp NowTimestamp();

// "jobs/ID" -> "ID" (an id stays as it is).
std::string JobIdOf(const std::string& name);

// A new job's id: its sequence number (ids sort by creation) and a random tail that keeps
// them unguessable.
std::string NewJobId(int64_t seq, uint64_t random);

// Names a new job: its id (returned) from `seq` and `random`, "jobs/ID", its create time
// and, when unset, the QUEUED state. Every store's Create and Split make their rows so.
std::string NameNewJob(v1::Job* job, int64_t seq, uint64_t random, absl::Time now = absl::Now());

// The request_id column is unique: it holds the tenant and the client's request id, the
// default tenant's bare (as stores before tenants held them). Request ids hold no control
// characters (the service refuses them), so the keys of two tenants never meet.
std::string ScopedRequestId(const std::string& tenant, const std::string& request_id);

// The blobs a job names: its input and its artifacts.
std::set<std::string> BlobsOf(const v1::Job& job);

// A stored record; kDataLoss when it does not parse. Records from before tenants are the
// default tenant's.
absl::StatusOr<v1::Job> ParseStoredJob(const std::string& bytes);

// A job's end as its worker reports it: the state, the end time, and the artifacts
// (SUCCEEDED) or the error.
void ApplyFinish(v1::Job* job, v1::JobState state, const v1::JobError& error,
                 const std::vector<v1::Artifact>& artifacts, absl::Time now = absl::Now());

// A QUEUED job cancelled: CANCELLED at once.
void ApplyCancelBeforeStart(v1::Job* job, absl::Time now = absl::Now());

// A RUNNING job whose worker was lost (lease expired, server restarted): CANCELLED when a
// cancel was asked, FAILED after max_attempts, QUEUED again otherwise.
// With `not_the_jobs_fault` the lost run is counted in lost_to_restarts, not against
// max_attempts.
void ApplyLostWorker(v1::Job* job, bool cancel_requested, int max_attempts,
                     bool not_the_jobs_fault = false, absl::Time now = absl::Now());

// The brick tasks of `parent` for a plan of `count` bricks: each its input, parameters and
// tenant, request id "<parent's>/brick/<index>", and bricks.parent / index / plan.
std::vector<v1::Job> BrickTasks(const v1::Job& parent, const v1::Artifact& plan, int count);

// `parent` split into the tasks named `names`: QUEUED again (its attempt not counted),
// waiting for them.
void ApplySplit(v1::Job* parent, const v1::Artifact& plan, const std::vector<std::string>& names);

// The most brick tasks one job may have.
inline constexpr int kMaxBricks = runtime::kMaxJobBricks;

// kFailedPrecondition unless `job` may be split (has bricks.size, is not a task, has no
// plan yet); kInvalidArgument for a count outside [1, kMaxBricks].
absl::Status CheckSplittable(const v1::Job& job, int count);

// Whether `job`, just finished, is a split job merged: its bricks' outputs are of no more
// use, and its tasks drop them (ApplyMerged), so that the blob store may let them go.
inline bool MergedSplitJob(const v1::Job& job) {
  return job.state() == v1::SUCCEEDED && job.bricks().count() > 0 && job.bricks().parent().empty();
}
void ApplyMerged(v1::Job* task);

// Whether a task in `state` keeps its split job waiting (QUEUED or RUNNING).
inline bool TaskPending(v1::JobState state) { return state == v1::QUEUED || state == v1::RUNNING; }

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_JOB_STORE_ROWS_H_
