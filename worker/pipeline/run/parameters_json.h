// Internal to the pipeline library: the parameters as a JSON object, for the report
// writer (which nests them) and the canonical text. Includes nlohmann/json.
#ifndef SHEETMESH_WORKER_PIPELINE_RUN_PARAMETERS_JSON_H_
#define SHEETMESH_WORKER_PIPELINE_RUN_PARAMETERS_JSON_H_

#include <nlohmann/json.hpp>

#include "worker/pipeline/run/parameter_types.h"
#include "worker/pipeline/run/pipeline_options.h"

namespace sheetmesh {

// Every parameter of `options` as nested objects by key path; see CanonicalParametersJson.
nlohmann::json ParametersJson(const PipelineOptions& options, bool include_local);

// The value as JSON.
nlohmann::json ToJson(const ParamValue& value);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_RUN_PARAMETERS_JSON_H_
