// RunJob: one leased job through the pipeline — input resolved, parameters converted,
// progress and cancellation through the host, outputs stored as artifacts.
#ifndef SHEETMESH_WORKER_RUNTIME_JOB_RUNNER_H_
#define SHEETMESH_WORKER_RUNTIME_JOB_RUNNER_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "worker/runtime/job_host.h"

namespace sheetmesh::runtime {

// Media type of an output file, by its extension.
std::string MediaTypeOf(const std::string& file_name);

// Runs `job` for `worker`, writing outputs under `scratch_dir` (removed afterwards).
// Returns the stored artifacts; errors of the pipeline pass through with their codes
// (kCancelled when the host asked to stop).
absl::StatusOr<std::vector<v1::Artifact>> RunJob(const v1::Job& job, const std::string& worker,
                                                 JobHost& host, const std::string& scratch_dir);

}  // namespace sheetmesh::runtime

#endif  // SHEETMESH_WORKER_RUNTIME_JOB_RUNNER_H_
