// The job's wire parameters as pipeline options: the one place proto meets the pipeline.
#ifndef SHEETMESH_WORKER_RUNTIME_JOB_PARAMETERS_H_
#define SHEETMESH_WORKER_RUNTIME_JOB_PARAMETERS_H_

#include <string>

#include "absl/status/statusor.h"
#include "sheetmesh/v1/jobs.pb.h"
#include "worker/pipeline/run/pipeline.h"

namespace sheetmesh::runtime {

// Pipeline options for `parameters` and `input` (read from `volume_path`): defaults, then
// parameters.config_json, then the typed fields. kInvalidArgument naming the field
// ("parameters.r = -1 must be positive") for a bad value.
absl::StatusOr<PipelineOptions> ToPipelineOptions(const v1::PipelineParameters& parameters,
                                                  const v1::JobInput& input,
                                                  const std::string& volume_path);

}  // namespace sheetmesh::runtime

#endif  // SHEETMESH_WORKER_RUNTIME_JOB_PARAMETERS_H_
