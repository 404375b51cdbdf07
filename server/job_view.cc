#include "server/job_view.h"

#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "server/bricked_jobs.h"

namespace sheetmesh::server {

absl::StatusOr<v1::Job> FreshJob(const ServiceContext& ctx, const std::string& tenant,
                                 const std::string& name) {
  SM_ASSIGN_OR_RETURN(v1::Job job, ctx.jobs->Get(name));
  if (job.tenant() != tenant) {
    return absl::NotFoundError(absl::StrCat(name, " does not exist"));
  }
  if (job.state() == v1::RUNNING) {
    if (auto p = ctx.host->Progress(job.name())) *job.mutable_progress() = *p;
  }
  if (IsSplit(job)) {
    // Its bricks: their progress is the job's while they run (a brick running here, fresher).
    SM_ASSIGN_OR_RETURN(std::vector<v1::Job> tasks, ctx.jobs->Tasks(job.name()));
    for (v1::Job& t : tasks) {
      if (t.state() != v1::RUNNING) continue;
      if (auto p = ctx.host->Progress(t.name())) *t.mutable_progress() = *p;
    }
    PresentSplit(&job, &tasks);
  }
  return job;
}

}  // namespace sheetmesh::server
