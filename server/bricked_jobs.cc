#include "server/bricked_jobs.h"

#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "server/job_store_rows.h"
#include "sheetmesh/v1/job_states.h"

namespace sheetmesh::server {

void PresentSplit(v1::Job* job, const std::vector<v1::Job>* tasks) {
  if (!IsSplit(*job)) return;
  const bool live = job->state() == v1::QUEUED;  // stored QUEUED, for its merge
  if (live) job->set_state(v1::RUNNING);
  if (tasks == nullptr) return;
  int ended = 0, succeeded = 0, running = 0;
  double work = 0;
  for (const v1::Job& t : *tasks) {
    if (v1::IsTerminal(t.state())) {
      ++ended;
      succeeded += t.state() == v1::SUCCEEDED;
      work += 1;
    } else if (t.state() == v1::RUNNING) {
      ++running;
      const v1::JobProgress& p = t.progress();
      // A brick's stages are read and select: the share of them done.
      if (p.stage_count() > 0 && p.stage_index() > 0) {
        work += (p.stage_index() - 1 + p.fraction()) / p.stage_count();
      }
    }
  }
  v1::JobBricks& b = *job->mutable_bricks();
  b.set_ended(ended);
  b.set_succeeded(succeeded);
  if (!live) return;
  v1::JobProgress& p = *job->mutable_progress();
  p.set_stage("bricks");
  p.set_stage_index(0);
  p.set_stage_count(0);
  p.set_fraction(tasks->empty() ? 0 : work / static_cast<double>(tasks->size()));
  p.set_message(
      ended == b.count()
          ? absl::StrCat("all ", b.count(), " bricks done; waiting for a worker to merge")
          : absl::StrCat(ended, " of ", b.count(), " bricks done, ", running, " running"));
}

absl::StatusOr<std::optional<v1::Job>> PrepareMerge(JobStore& store, v1::Job job,
                                                    const std::string& worker) {
  if (!IsSplit(job)) return std::optional<v1::Job>(std::move(job));
  SM_ASSIGN_OR_RETURN(std::vector<v1::Job> tasks, store.Tasks(job.name()));
  job.mutable_bricks()->clear_outputs();
  const v1::Job* failed = nullptr;
  for (const v1::Job& t : tasks) {
    if (t.state() == v1::SUCCEEDED && t.artifacts_size() == 1) {
      *job.mutable_bricks()->add_outputs() = t.artifacts(0);
    } else if (failed == nullptr ||
               (failed->state() == v1::CANCELLED && t.state() != v1::CANCELLED)) {
      failed = &t;  // the first that failed, else the first cancelled
    }
  }
  if (failed == nullptr && static_cast<int>(tasks.size()) != job.bricks().count()) {
    v1::JobError e;
    e.set_code(static_cast<int>(absl::StatusCode::kDataLoss));
    e.set_message(absl::StrCat("the job has ", tasks.size(), " of its ", job.bricks().count(),
                               " brick tasks stored: it cannot be merged"));
    SM_RETURN_IF_ERROR(store.Finish(job.name(), worker, v1::FAILED, e, {}).status());
    return std::optional<v1::Job>();
  }
  if (failed == nullptr) return std::optional<v1::Job>(std::move(job));
  v1::JobError e;
  const v1::JobState state = failed->state() == v1::CANCELLED ? v1::CANCELLED : v1::FAILED;
  e.set_code(failed->error().code() != 0 ? failed->error().code()
                                         : static_cast<int>(absl::StatusCode::kInternal));
  e.set_message(absl::StrCat(
      "brick ", failed->bricks().index(), " of ", job.bricks().count(), " (", failed->name(), ") ",
      state == v1::CANCELLED ? "was cancelled" : "failed", ": ", failed->error().message()));
  SM_RETURN_IF_ERROR(store.Finish(job.name(), worker, state, e, {}).status());
  return std::optional<v1::Job>();
}

void TaskEnded(JobStore& store, JobEvents& events, const v1::Job& task) {
  const std::string& parent = task.bricks().parent();
  if (parent.empty()) return;
  if (task.state() == v1::FAILED) {
    absl::StatusOr<v1::Job> job = store.Get(parent);
    if (job.ok()) CancelTasks(store, *job).IgnoreError();
  }
  events.Notify(parent);
}

void LostJobsEnded(JobStore& store, JobEvents& events, const std::vector<v1::Job>& ended) {
  for (const v1::Job& job : ended) {
    events.NotifyFinished(job.name());
    TaskEnded(store, events, job);
  }
}

absl::Status CancelTasks(JobStore& store, const v1::Job& job) {
  return store.CancelTasks(job.name()).status();
}

absl::Status CheckSplit(JobStore& store, const SplitLimits& limits, const std::string& name,
                        int count) {
  if (count > limits.max_brick_tasks) {
    return absl::InvalidArgumentError(absl::StrCat(
        name, ": its plan has ", count, " bricks, more than the server runs for one job "
        "(max_brick_tasks = ", limits.max_brick_tasks, "): give larger bricks (the job's bricks)"));
  }
  SM_ASSIGN_OR_RETURN(const int64_t jobs, store.CountInState(v1::QUEUED));
  SM_ASSIGN_OR_RETURN(const int64_t tasks, store.CountQueuedTasks());
  if (jobs + tasks + count > limits.max_queued_jobs) {
    return absl::ResourceExhaustedError(absl::StrCat(
        name, ": its ", count, " bricks would take the queue (", jobs, " jobs and ", tasks,
        " brick tasks) past the server's limit (max_queued_jobs = ", limits.max_queued_jobs,
        "); retry later, or give larger bricks"));
  }
  return absl::OkStatus();
}

}  // namespace sheetmesh::server
