#include "server/job_view.h"

#include "absl/strings/str_cat.h"
#include "common/status_macros.h"

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
  return job;
}

}  // namespace sheetmesh::server
