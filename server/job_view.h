// A job as a caller sees it: the stored job with the running job's live progress, within
// the caller's tenant. The job service and the watch share it.
#ifndef SHEETMESH_SERVER_JOB_VIEW_H_
#define SHEETMESH_SERVER_JOB_VIEW_H_

#include <string>

#include "absl/status/statusor.h"
#include "server/service_context.h"
#include "sheetmesh/v1/job_states.h"
#include "sheetmesh/v1/jobs.pb.h"

namespace sheetmesh::server {

// The stored job with the running job's live progress; kNotFound (as for a job that does
// not exist) when it is not `tenant`'s.
absl::StatusOr<v1::Job> FreshJob(const ServiceContext& ctx, const std::string& tenant,
                                 const std::string& name);

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_JOB_VIEW_H_
