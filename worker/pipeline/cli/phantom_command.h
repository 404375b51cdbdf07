// `sheetmesh-pipeline phantom` and `convert`: write a synthetic rock volume with its JSON
// ground truth, or copy a volume into another format.
#ifndef SHEETMESH_WORKER_PIPELINE_CLI_PHANTOM_COMMAND_H_
#define SHEETMESH_WORKER_PIPELINE_CLI_PHANTOM_COMMAND_H_

#include <ostream>
#include <string>

#include "absl/status/status.h"
#include "worker/pipeline/phantom/phantom.h"
#include "worker/pipeline/volume/volume_open.h"

namespace sheetmesh {

struct PhantomCommandOptions {
  PhantomOptions phantom;
  std::string output;                        // the volume file (or folder for tiff-folder)
  VolumeFormat format = VolumeFormat::kRaw;  // output format
  std::string truth_path;                    // ground truth JSON ("" = <output>.truth.json)
};

// Generates and writes the phantom, then prints a one-line summary to `out`.
absl::Status RunPhantom(const PhantomCommandOptions& options, std::ostream& out);

// `sheetmesh-pipeline convert`: copies a volume into another format slab by slab.
absl::Status RunConvert(const std::string& input, const OpenOptions& open,
                        const std::string& output, VolumeFormat format, std::ostream& out);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_CLI_PHANTOM_COMMAND_H_
