// Pipeline parameters on the command line: every row of the parameter table is a flag
// named after it (`--separate_r=6`, `--separate.r 6`, `--separate-r=6`; `--volume_mesh`,
// `--novolume_mesh` for booleans). They are taken out of argv before Abseil parses the
// command's other flags.
#ifndef SHEETMESH_WORKER_PIPELINE_CLI_PARAMETER_FLAGS_H_
#define SHEETMESH_WORKER_PIPELINE_CLI_PARAMETER_FLAGS_H_

#include <functional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "worker/pipeline/run/parameters.h"

namespace sheetmesh {

struct ParameterFlags {
  std::vector<char*> rest;        // argv without the parameter flags (argv[0] first)
  ParameterBuilder given;         // the parameter flags, in order, checked
  std::vector<std::string> keys;  // their keys, in order
};

// Takes the parameter flags out of argv. `accepts` says which parameters the command
// uses. kInvalidArgument naming the flag for a bad value, a parameter the command does
// not use, or a flag renamed since 0.8 (naming its new name).
absl::StatusOr<ParameterFlags> TakeParameterFlags(
    int argc, char** argv, const std::function<bool(const ParamSpec&)>& accepts,
    absl::string_view command);

// The parameter flags for --help: "  --separate_r=5  number in (0, 1000], voxels\n      r of
// the SCVD built for separation\n", for the parameters `accepts` takes.
std::string ParameterFlagsHelp(const std::function<bool(const ParamSpec&)>& accepts);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_CLI_PARAMETER_FLAGS_H_
