// OpenVDB volumes: read any scalar grid of a .vdb file as a volume, and write volumes as
// sparse grids. OpenVDB stays inside vdb_io.cc (voxel/voxel_set_vdb.h writes sheet sets).
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_VDB_IO_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_VDB_IO_H_

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "absl/status/statusor.h"
#include "worker/pipeline/volume/volume_sink.h"
#include "worker/pipeline/volume/volume_source.h"

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

// A row of voxels [x0, x1) at (y, z) of a sparse volume.
struct SparseRun {
  int32_t x0 = 0, x1 = 0, y = 0, z = 0;
};

// Writes the voxels of `runs` (a box of `dims`) as a Bool grid named `grid_name`, and,
// when `labels` is not empty (one per voxel, in run order), a Float grid (python3-openvdb reads no
// Int32 grid)
// "<grid_name>_labels". kInvalidArgument when the label count differs from the voxel count;
// kInternal when OpenVDB fails. Atomic.
absl::Status WriteSparseVdb(const std::string& path, const Dims& dims,
                            std::span<const SparseRun> runs, std::span<const int32_t> labels,
                            const Placement& placement, const std::string& grid_name);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_VDB_IO_H_
