// Jobs run as bricks (JobBricks in jobs.proto), the server's side: what a caller sees of a
// split job while its bricks run, what the worker that merges is handed, and what follows
// when a brick task ends or the job is cancelled. The store keeps the tasks (JobStore::Split,
// Tasks); the workers plan, run and merge (worker/runtime/job_runner.h).
#ifndef SHEETMESH_SERVER_BRICKED_JOBS_H_
#define SHEETMESH_SERVER_BRICKED_JOBS_H_

#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "server/job_events.h"
#include "server/job_store.h"
#include "sheetmesh/v1/jobs.pb.h"

namespace sheetmesh::server {

// Whether `job` has been split into brick tasks (it is not one).
inline bool IsSplit(const v1::Job& job) {
  return job.bricks().count() > 0 && job.bricks().parent().empty();
}

// A split job as callers see it: RUNNING while its bricks run (the store keeps it QUEUED,
// for the merge); with `tasks` (its tasks as stored, in order) how many ended and
// succeeded, and while they run its progress: stage "bricks", the fraction of their work.
void PresentSplit(v1::Job* job, const std::vector<v1::Job>* tasks);

// A split job just leased, for the merge: its bricks' outputs in bricks.outputs, in the
// plan's order. When a brick did not succeed the job ends here (FAILED naming the brick and
// its error, or CANCELLED) and nullopt comes back: lease another.
absl::StatusOr<std::optional<v1::Job>> PrepareMerge(JobStore& store, v1::Job job,
                                                    const std::string& worker);

// After a brick task ended (FinishJob, a lost worker): a failed brick cancels its siblings
// (the job will fail); the job's watchers hear of it.
void TaskEnded(JobStore& store, JobEvents& events, const v1::Job& task);

// After RequeueExpired ended `ended` (their workers were lost once too often, or they were
// cancelled meanwhile): their watchers hear of it at once, and a brick task among them is
// handled as one that finished (TaskEnded: a failed brick cancels its siblings).
void LostJobsEnded(JobStore& store, JobEvents& events, const std::vector<v1::Job>& ended);

// Cancels the tasks of a split job at once (the job itself is cancelled by the caller).
absl::Status CancelTasks(JobStore& store, const v1::Job& job);

// What a job may split into.
struct SplitLimits {
  int max_brick_tasks = 512;       // bricks of one job
  int64_t max_queued_jobs = 1000;  // jobs and brick tasks the queue may hold
};

// Whether the job `name` may split into `count` brick tasks: kInvalidArgument beyond
// max_brick_tasks, kResourceExhausted when its tasks would take the queue (jobs and brick
// tasks) past max_queued_jobs; each naming the job, the count and the limit.
absl::Status CheckSplit(JobStore& store, const SplitLimits& limits, const std::string& name,
                        int count);

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_BRICKED_JOBS_H_
