// `sheetmesh-pipeline phantom`: writes a synthetic rock volume and its JSON ground truth.
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

// The small sample volume the demo meshes: three crossing rough sheets with holes, one of
// them fragmented, and specks.
PhantomOptions SamplePhantomOptions();

// Generates and writes the phantom, then prints a one-line summary to `out`.
absl::Status RunPhantom(const PhantomCommandOptions& options, std::ostream& out);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_CLI_PHANTOM_COMMAND_H_
