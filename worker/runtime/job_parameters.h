// A job's parameters: the wire form (typed fields, config_json, the input's format)
// resolved once, through the pipeline's parameter table, into the canonical JSON the job
// stores and the worker runs. The one place proto meets the pipeline's options.
#ifndef SHEETMESH_WORKER_RUNTIME_JOB_PARAMETERS_H_
#define SHEETMESH_WORKER_RUNTIME_JOB_PARAMETERS_H_

#include <string>

#include "absl/status/statusor.h"
#include "sheetmesh/v1/jobs.pb.h"
#include "worker/pipeline/run/pipeline.h"

namespace sheetmesh::runtime {

// The canonical parameter JSON of a job: defaults, then parameters.config_json, then the
// typed fields of `parameters` and `input.format` (each field named as the parameter
// table names it). Equal settings always give equal text, however they were written.
// kInvalidArgument naming the field ("parameters.r = -1.0 must be a number in (0,
// 4096]") for a bad value, and for parameters a job may not set (paths, programs).
absl::StatusOr<std::string> ResolveJobParameters(const v1::PipelineParameters& parameters,
                                                 const v1::JobInput& input);

// The pipeline options of `canonical` (from ResolveJobParameters), reading `volume_path`.
// kInvalidArgument when it does not parse.
absl::StatusOr<PipelineOptions> OptionsFromResolved(const std::string& canonical,
                                                    const std::string& volume_path);

// The pipeline options a job runs: its canonical parameters (job.resolved_parameters, or
// resolved now for a job stored before they were), reading `volume_path`.
// kInvalidArgument as above.
absl::StatusOr<PipelineOptions> JobPipelineOptions(const v1::Job& job,
                                                   const std::string& volume_path);

// The fewest voxels a brick a job asks for may hold (its edges all given).
inline constexpr int64_t kMinJobBrickVoxels = 16 * 16 * 16;

// kInvalidArgument naming the field `bricks` and its text unless it is a brick size a job
// may ask for (JobBricks.size: "auto", "512", "512x512x256"; no edge below 0, and bricks of
// at least kMinJobBrickVoxels). How many bricks the plan makes is bounded when the job
// splits (the server's max_brick_tasks).
absl::Status CheckBrickRequest(const std::string& bricks);

}  // namespace sheetmesh::runtime

#endif  // SHEETMESH_WORKER_RUNTIME_JOB_PARAMETERS_H_
