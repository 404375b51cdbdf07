// OpenVDB volumes: read any scalar grid of a .vdb file as a volume, and write volumes,
// sheet sets and labelled models as sparse grids. OpenVDB stays inside vdb_io.cc.
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_VDB_IO_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_VDB_IO_H_

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "absl/status/statusor.h"
#include "worker/pipeline/volume/volume_sink.h"
#include "worker/pipeline/volume/volume_source.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// Opens grid `grid_name` (empty: the first scalar grid) of a .vdb file as a volume.
// Grids written by sheetmesh keep their dims, dtype and placement; for others the box is
// the active voxels' bounding box, float/double grids read as float32, integer grids as
// float32, bool and mask grids as uint8 (1 = active). kNotFound for a missing grid,
// kInvalidArgument for a non-scalar grid or an unreadable file.
absl::StatusOr<std::unique_ptr<VolumeSource>> OpenVdbVolume(const std::string& path,
                                                            const std::string& grid_name = "",
                                                            const VolumeLimits& limits = {});

// Writes a volume as one sparse grid named "volume": Int32 for uint8/uint16, Float for
// float32; voxels equal to 0 stay inactive background. The file appears atomically.
absl::StatusOr<std::unique_ptr<VolumeSink>> CreateVdbWriter(const std::string& path,
                                                            const VolumeInfo& info);

// Writes `set` as a mask grid named `grid_name`, and, when `labels` is not empty (one per
// voxel of `set`), an Int32 grid "<grid_name>_labels". Atomic.
absl::Status WriteVoxelSetVdb(const std::string& path, const VoxelSet& set,
                              std::span<const int32_t> labels, const Placement& placement,
                              const std::string& grid_name = "sheet");

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_VDB_IO_H_
