// VolumeSink: a volume written slice by slice; the output appears only when Finish()
// succeeds, so an interrupted write never leaves a half-written volume behind.
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_VOLUME_SINK_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_VOLUME_SINK_H_

#include <cstddef>
#include <cstdint>
#include <span>

#include "absl/status/status.h"
#include "common/byte_order.h"
#include "worker/pipeline/volume/volume_source.h"

namespace sheetmesh {

// Not thread-safe.
class VolumeSink {
 public:
  virtual ~VolumeSink() = default;

  // Appends `count` slices (x fastest, native byte order, info().dtype) after those already
  // written. kFailedPrecondition past the last slice.
  virtual absl::Status WriteSlices(int64_t count, std::span<const std::byte> data) = 0;
  // Completes the volume and makes it visible at its path. kFailedPrecondition if fewer
  // than nz slices were written.
  virtual absl::Status Finish() = 0;

  const VolumeInfo& info() const { return info_; }

 protected:
  // Checks that `count` more slices of `bytes` fit; advances the slice counter.
  absl::Status Advance(int64_t count, size_t bytes);
  absl::Status CheckComplete() const;

  VolumeInfo info_;
  int64_t slices_written_ = 0;
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_VOLUME_SINK_H_
