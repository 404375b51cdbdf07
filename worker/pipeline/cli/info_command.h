// `sheetmesh-pipeline info`: what a volume holds — dims, dtype, placement, sheet voxels,
// thickness statistics and connected components — as text or JSON.
#ifndef SHEETMESH_WORKER_PIPELINE_CLI_INFO_COMMAND_H_
#define SHEETMESH_WORKER_PIPELINE_CLI_INFO_COMMAND_H_

#include <ostream>

#include "absl/status/status.h"
#include "worker/pipeline/voxel/components.h"
#include "worker/pipeline/voxel/sheet_input.h"

namespace sheetmesh {

struct InfoOptions {
  SheetInput input;
  Connectivity connectivity = Connectivity::k6;  // for the component count
  int largest_components = 10;                   // sizes listed, largest first
  bool json = false;                             // JSON instead of text
};

// Writes the report to `out`. Errors of reading or selecting pass through.
absl::Status RunInfo(const InfoOptions& options, std::ostream& out);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_CLI_INFO_COMMAND_H_
