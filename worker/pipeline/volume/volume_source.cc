#include "worker/pipeline/volume/volume_source.h"

#include <sys/mman.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <limits>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/machine.h"

namespace sheetmesh {

MappedSlices& MappedSlices::operator=(MappedSlices&& o) noexcept {
  if (this != &o) {
    if (base_ != nullptr) ::munmap(base_, length_);
    base_ = o.base_;
    length_ = o.length_;
    data_ = o.data_;
    o.base_ = nullptr;
    o.length_ = 0;
    o.data_ = {};
  }
  return *this;
}

MappedSlices::~MappedSlices() {
  if (base_ != nullptr) ::munmap(base_, length_);
}

int BytesPerVoxel(DType dtype) {
  switch (dtype) {
    case DType::kUInt8:
      return 1;
    case DType::kUInt16:
      return 2;
    case DType::kFloat32:
      return 4;
  }
  return 1;
}

absl::string_view DTypeName(DType dtype) {
  switch (dtype) {
    case DType::kUInt8:
      return "uint8";
    case DType::kUInt16:
      return "uint16";
    case DType::kFloat32:
      return "float32";
  }
  return "?";
}

absl::StatusOr<DType> ParseDType(absl::string_view name) {
  const std::string n = absl::AsciiStrToLower(name);
  if (n == "uint8" || n == "u8") return DType::kUInt8;
  if (n == "uint16" || n == "u16") return DType::kUInt16;
  if (n == "float32" || n == "f32" || n == "float") return DType::kFloat32;
  return absl::InvalidArgumentError(
      absl::StrCat("dtype '", name, "' is not supported; use uint8, uint16 or float32"));
}

absl::StatusOr<ByteOrder> ParseByteOrder(absl::string_view name) {
  const std::string n = absl::AsciiStrToLower(name);
  if (n == "little" || n == "le") return ByteOrder::kLittle;
  if (n == "big" || n == "be") return ByteOrder::kBig;
  return absl::InvalidArgumentError(
      absl::StrCat("byte order '", name, "' is not supported; use little or big"));
}

absl::Status VolumeSource::CheckSliceRequest(int64_t z0, int64_t count, size_t out_bytes) const {
  const Dims& d = info_.dims;
  if (z0 < 0 || count < 0 || z0 + count > d.nz ||
      out_bytes != static_cast<size_t>(count * d.nx * d.ny * BytesPerVoxel(info_.dtype))) {
    return absl::InvalidArgumentError(
        absl::StrCat(info_.path, ": bad slice request z0=", z0, " count=", count));
  }
  return absl::OkStatus();
}

absl::Status CheckDims(const Dims& dims, DType dtype, const VolumeLimits& limits,
                       absl::string_view what) {
  if (dims.nx <= 0 || dims.ny <= 0 || dims.nz <= 0) {
    return absl::InvalidArgumentError(absl::StrCat(what, ": dims ", dims.nx, "x", dims.ny, "x",
                                                   dims.nz, " must all be positive"));
  }
  for (int64_t e : {dims.nx, dims.ny, dims.nz}) {
    if (e > limits.max_extent) {
      return absl::InvalidArgumentError(absl::StrCat(what, ": dims ", dims.ToString(),
                                                     " have an extent above the limit of ",
                                                     limits.max_extent));
    }
  }
  // Extents are each <= 2^20 here, so the product fits in 63 bits only if checked stepwise.
  const int64_t kMax = std::numeric_limits<int64_t>::max() / 4;
  if (dims.nx > kMax / dims.ny || dims.nx * dims.ny > kMax / dims.nz) {
    return absl::InvalidArgumentError(
        absl::StrCat(what, ": dims ", dims.ToString(), " overflow a 64-bit voxel count"));
  }
  if (dims.num_voxels() > limits.max_voxels) {
    return absl::ResourceExhaustedError(
        absl::StrCat(what, ": dims ", dims.ToString(), " hold ", dims.num_voxels(), " voxels of ",
                     DTypeName(dtype), ", above the limit of ", limits.max_voxels, " voxels"));
  }
  return absl::OkStatus();
}

absl::Status AsInputError(absl::Status status) {
  if (status.code() != absl::StatusCode::kDataLoss) return status;
  return absl::InvalidArgumentError(status.message());
}

absl::Status CheckCompressionRatio(int64_t decoded_bytes, int64_t stored_bytes, double max_ratio,
                                   absl::string_view what) {
  if (decoded_bytes <= 0) return absl::OkStatus();
  const double ratio = static_cast<double>(decoded_bytes) / std::max<int64_t>(stored_bytes, 1);
  if (ratio <= max_ratio) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrFormat(
      "%s declares %d bytes of voxels but holds %d bytes of data for them (%.0f:1; its "
      "compression reaches at most %.0f:1): cut short, or a header that does not describe "
      "its data",
      what, decoded_bytes, stored_bytes, ratio, max_ratio));
}

int64_t MemoryBudget(const VolumeLimits& limits) {
  if (limits.memory_bytes > 0) return limits.memory_bytes;
  int64_t budget = static_cast<int64_t>(PhysicalMemoryBytes(uint64_t{16} << 30) / 4);
  // Within a process whose address space is limited (a job's child), half of that limit.
  struct rlimit as;
  if (::getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY) {
    budget = std::min<int64_t>(budget, static_cast<int64_t>(as.rlim_cur / 2));
  }
  return budget;
}

absl::Status CheckAllocation(int64_t bytes, const VolumeLimits& limits, absl::string_view what) {
  if (bytes < 0) {
    return absl::InvalidArgumentError(absl::StrCat(what, " would need a size that overflows"));
  }
  const int64_t budget = MemoryBudget(limits);
  if (bytes > budget) {
    return absl::ResourceExhaustedError(absl::StrCat(
        what, " needs ", bytes, " bytes at once, over the memory budget of ", budget, " bytes"));
  }
  return absl::OkStatus();
}

}  // namespace sheetmesh
