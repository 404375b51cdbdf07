#include "worker/pipeline/volume/volume_sink.h"

#include "absl/strings/str_cat.h"

namespace sheetmesh {

absl::Status VolumeSink::Advance(int64_t count, size_t bytes) {
  const Dims& d = info_.dims;
  if (count < 0 || slices_written_ + count > d.nz) {
    return absl::FailedPreconditionError(absl::StrCat(
        info_.path, ": writing ", count, " slices after ", slices_written_, " exceeds nz ", d.nz));
  }
  const uint64_t expected = static_cast<uint64_t>(count) * d.nx * d.ny * BytesPerVoxel(info_.dtype);
  if (bytes != expected) {
    return absl::InvalidArgumentError(
        absl::StrCat(info_.path, ": ", count, " slices need ", expected, " bytes, got ", bytes));
  }
  slices_written_ += count;
  return absl::OkStatus();
}

absl::Status VolumeSink::CheckComplete() const {
  if (slices_written_ != info_.dims.nz) {
    return absl::FailedPreconditionError(absl::StrCat(
        info_.path, ": only ", slices_written_, " of ", info_.dims.nz, " slices were written"));
  }
  return absl::OkStatus();
}

}  // namespace sheetmesh
