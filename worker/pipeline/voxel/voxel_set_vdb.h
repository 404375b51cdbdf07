// Sheet sets and labelled models as sparse OpenVDB grids (the model.vdb artifact).
// OpenVDB stays inside voxel_set_vdb.cc.
#ifndef SHEETMESH_WORKER_PIPELINE_VOXEL_VOXEL_SET_VDB_H_
#define SHEETMESH_WORKER_PIPELINE_VOXEL_VOXEL_SET_VDB_H_

#include <cstdint>
#include <span>
#include <string>

#include "absl/status/status.h"
#include "common/types.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// Writes `set` as a Bool grid named `grid_name`, and, when `labels` is not empty (one per
// voxel of `set`), a Float grid "<grid_name>_labels". kInvalidArgument when the label
// count differs from the voxel count; kInternal when OpenVDB fails. Atomic.
absl::Status WriteVoxelSetVdb(const std::string& path, const VoxelSet& set,
                              std::span<const int32_t> labels, const Placement& placement,
                              const std::string& grid_name = "sheet");

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOXEL_VOXEL_SET_VDB_H_
