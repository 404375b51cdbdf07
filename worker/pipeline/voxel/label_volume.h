// Writes a labelled voxel model as a dense label volume (uint16: label + 1, 0 background)
// in any volume format, slab by slab, so a paper-scale model never needs its box in memory.
#ifndef SHEETMESH_WORKER_PIPELINE_VOXEL_LABEL_VOLUME_H_
#define SHEETMESH_WORKER_PIPELINE_VOXEL_LABEL_VOLUME_H_

#include <string>

#include "absl/status/status.h"
#include "worker/pipeline/volume/volume_open.h"
#include "worker/pipeline/voxel/labelled_voxels.h"

namespace sheetmesh {

// kInvalidArgument when a label exceeds 65534; writer errors pass through. Atomic.
absl::Status WriteLabelVolume(const LabelledVoxels& model, const std::string& path,
                              VolumeFormat format, const Placement& placement);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOXEL_LABEL_VOLUME_H_
