// RunJob: one leased job through the pipeline — input resolved, parameters converted,
// progress and cancellation through the host, outputs stored as artifacts.
#ifndef SHEETMESH_WORKER_RUNTIME_JOB_RUNNER_H_
#define SHEETMESH_WORKER_RUNTIME_JOB_RUNNER_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "worker/runtime/job_host.h"
#include "worker/runtime/job_process.h"

namespace sheetmesh::runtime {

// Media type of an output file, by its extension.
std::string MediaTypeOf(const std::string& file_name);

// How jobs run: in a child process (the default; see job_process.h) or in this one.
struct JobRunOptions {
  std::string scratch_dir = "/tmp";  // each job writes into a folder of its own here
  bool isolate = true;               // run the pipeline in a child process
  std::string program;               // the child's program ("": this one, /proc/self/exe)
  JobLimits limits;                  // the child's limits (memory, CPU, wall)
};

// How a job ended: OK with its artifacts, or an error with the artifacts of what the run
// kept (a failed volume stage keeps the surface, its score, the previews and the report).
struct JobOutcome {
  absl::Status status;
  std::vector<v1::Artifact> artifacts;
  // The job was planned and split into brick tasks (JobHost::Split): nothing to finish.
  bool split = false;
};

// Runs `job` for `worker`, writing outputs under options.scratch_dir (removed afterwards),
// and stores the outputs as artifacts. Errors of the pipeline pass through with their codes
// (kCancelled when the host asked to stop), and an isolated run that crashes or passes a
// limit fails naming why (job_process.h).
JobOutcome RunJob(const v1::Job& job, const std::string& worker, JobHost& host,
                  const JobRunOptions& options);

}  // namespace sheetmesh::runtime

#endif  // SHEETMESH_WORKER_RUNTIME_JOB_RUNNER_H_
