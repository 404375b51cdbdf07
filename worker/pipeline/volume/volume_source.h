// VolumeSource: a volume read slice by slice, so that no reader needs the whole box in
// memory. Every reader (raw, TIFF, NRRD, VDB) implements it.
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_VOLUME_SOURCE_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_VOLUME_SOURCE_H_

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "common/types.h"

namespace sheetmesh {

// Voxel value types the readers accept.
enum class DType { kUInt8, kUInt16, kFloat32 };

// Bytes of one voxel of `dtype`.
int BytesPerVoxel(DType dtype);
// "uint8", "uint16", "float32".
absl::string_view DTypeName(DType dtype);
// Parses "uint8"/"u8", "uint16"/"u16", "float32"/"f32"/"float". kInvalidArgument otherwise,
// naming the value and the accepted ones.
absl::StatusOr<DType> ParseDType(absl::string_view name);

enum class ByteOrder { kLittle, kBig };
absl::StatusOr<ByteOrder> ParseByteOrder(absl::string_view name);  // "little"/"big"

// What a reader knows about its volume before reading voxels.
struct VolumeInfo {
  std::string path;    // the file or folder, for messages
  std::string format;  // "raw", "tiff", "tiff-folder", "png-folder", "dicom-series", ...
  Dims dims;
  DType dtype = DType::kUInt8;
  Placement placement;
};

// Limits that protect readers from impossible requests.
// What a reader may do: how big a volume may be, how much memory reading it may take, and
// which other files it may open.
struct VolumeLimits {
  int64_t max_voxels = int64_t{1} << 37;  // dims beyond this are kResourceExhausted
  int64_t max_extent = int64_t{1} << 20;  // any one axis beyond this is kInvalidArgument
  // The memory a reader may allocate at once (a slice, a strip, a tile): a header declaring
  // more is kResourceExhausted before anything is allocated. 0: a quarter of the machine's
  // memory.
  int64_t memory_bytes = 0;
  // Files a volume names itself (a detached NRRD's data file): with confine_named_files,
  // only under named_file_roots (after following links), and none when that is empty.
  bool confine_named_files = false;
  std::vector<std::string> named_file_roots;
};

// limits.memory_bytes, or when it is 0 a quarter of the machine's memory (and at most half of
// this process's address-space limit, where it has one).
int64_t MemoryBudget(const VolumeLimits& limits);

// kResourceExhausted when `bytes` (what `what` needs at once) exceed the budget, naming both;
// kInvalidArgument when `bytes` is negative or overflowed.
absl::Status CheckAllocation(int64_t bytes, const VolumeLimits& limits, absl::string_view what);

// What a compressed file may decode to: a header declaring `decoded_bytes` from
// `stored_bytes` of compressed data beyond `max_ratio` (the best the format's coder can do
// on constant data: deflate 1032:1) describes data the file does not hold, and would make a
// few bytes cost gigabytes or minutes. kInvalidArgument naming `what`, both sizes and the
// ratio; ok otherwise.
absl::Status CheckCompressionRatio(int64_t decoded_bytes, int64_t stored_bytes, double max_ratio,
                                   absl::string_view what);

// The status of a read of an input file, with kDataLoss (the file ended early: the user's
// file is bad, not the system's storage) as kInvalidArgument.
absl::Status AsInputError(absl::Status status);

// Checks dims against `limits`: each extent positive, the product without overflow and
// within max_voxels. `what` names the source in the message.
absl::Status CheckDims(const Dims& dims, DType dtype, const VolumeLimits& limits,
                       absl::string_view what);

// Slices of a file mapped into memory; unmapped when destroyed. Movable.
class MappedSlices {
 public:
  MappedSlices() = default;
  MappedSlices(void* base, size_t length, std::span<const std::byte> data)
      : base_(base), length_(length), data_(data) {}
  MappedSlices(MappedSlices&& o) noexcept { *this = std::move(o); }
  MappedSlices& operator=(MappedSlices&& o) noexcept;
  ~MappedSlices();

  std::span<const std::byte> data() const { return data_; }

 private:
  void* base_ = nullptr;
  size_t length_ = 0;
  std::span<const std::byte> data_;
};

// A span of a file's bytes.
struct FileRange {
  int64_t offset = 0;
  int64_t length = 0;
  friend bool operator==(const FileRange&, const FileRange&) = default;
};

// A volume readable slice by slice. Not thread-safe; one reader per thread.
class VolumeSource {
 public:
  virtual ~VolumeSource() = default;

  // The bytes of the file info().path names that opening it again and reading slices
  // [z0, z0 + count) read, when the reader reads no others (one file whose slices lie in it
  // as they are: raw, NRRD with raw data attached); nullopt when it may read any. What a
  // worker fetches of a volume for one brick (worker/pipeline/brick/bricks.h).
  virtual std::optional<std::vector<FileRange>> BytesRead(int64_t z0, int64_t count) const {
    return std::nullopt;
  }

  // Whether MapSlices() works: files whose voxels lie on disk as they are in memory.
  virtual bool CanMap() const { return false; }
  // Maps slices [z0, z0 + count) without copying (same layout as ReadSlices). Mapped pages
  // leave the process when the result is destroyed, so memory stays at one slab.
  // kUnimplemented unless CanMap().
  virtual absl::StatusOr<MappedSlices> MapSlices(int64_t z0, int64_t count) {
    return absl::UnimplementedError("this reader cannot map slices");
  }

  const VolumeInfo& info() const { return info_; }

  // Reads slices [z0, z0 + count) into `out`, x fastest, then y, then z, in native byte
  // order. Sequential reads in increasing z are fastest; readers of compressed streams may
  // restart to go back. REQUIRES: out.size() == count * nx * ny * BytesPerVoxel(dtype),
  // 0 <= z0, z0 + count <= nz. kInvalidArgument when the file is broken (truncated,
  // corrupt), naming the file and the slice.
  virtual absl::Status ReadSlices(int64_t z0, int64_t count, std::span<std::byte> out) = 0;

 protected:
  // kInvalidArgument unless [z0, z0 + count) lies in the volume and `out_bytes` is what
  // those slices take: the shared precondition of every ReadSlices.
  absl::Status CheckSliceRequest(int64_t z0, int64_t count, size_t out_bytes) const;

  VolumeInfo info_;
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_VOLUME_SOURCE_H_
