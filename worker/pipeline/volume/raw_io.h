// Raw volumes: headerless voxel arrays (x fastest), optionally after a fixed-size header.
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_RAW_IO_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_RAW_IO_H_

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "worker/pipeline/volume/volume_sink.h"
#include "worker/pipeline/volume/volume_source.h"

namespace sheetmesh {

struct RawOptions {
  Dims dims;                                  // required: the file holds no dims
  DType dtype = DType::kUInt8;                // voxel type
  ByteOrder byte_order = ByteOrder::kLittle;  // of multi-byte voxels in the file
  int64_t header_bytes = 0;                   // bytes to skip before the first voxel
  Placement placement;                        // spacing and origin (the file holds none)
};

// Opens a raw volume. kInvalidArgument when dims are not positive or the file size is not
// header_bytes + voxels * bytes-per-voxel (the message names both sizes);
// kResourceExhausted above `limits`; kNotFound when the file is missing.
absl::StatusOr<std::unique_ptr<VolumeSource>> OpenRawVolume(const std::string& path,
                                                            const RawOptions& options,
                                                            const VolumeLimits& limits = {});

// Writes a raw volume of `info` (dims, dtype) to `path` in `byte_order`, no header.
absl::StatusOr<std::unique_ptr<VolumeSink>> CreateRawWriter(
    const std::string& path, const VolumeInfo& info, ByteOrder byte_order = ByteOrder::kLittle);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_RAW_IO_H_
