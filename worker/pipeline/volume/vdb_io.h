// OpenVDB volumes: read any scalar grid of a .vdb file as a volume, and write volumes as
// sparse grids. OpenVDB stays inside vdb_io.cc (voxel/voxel_set_vdb.h writes sheet sets).
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_VDB_IO_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_VDB_IO_H_

#include <cstdint>
#include <memory>
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

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_VDB_IO_H_
