#include "worker/pipeline/volume/raw_io.h"

#include <sys/mman.h>
#include <unistd.h>

#include <vector>

#include "absl/strings/str_cat.h"
#include "common/file_util.h"
#include "common/status_macros.h"

namespace sheetmesh {
namespace {

bool NeedsSwap(ByteOrder order) { return (order == ByteOrder::kLittle) != NativeIsLittleEndian(); }

class RawSource : public VolumeSource {
 public:
  RawSource(ScopedFd fd, const RawOptions& options, VolumeInfo info)
      : fd_(std::move(fd)), options_(options) {
    info_ = std::move(info);
  }

  // No MapSlices: a mapped file that shrinks while it is read kills the process with SIGBUS;
  // read() says "the file ends at byte N" instead.

  // Opening reads nothing (it checks the file's size).
  std::optional<std::vector<FileRange>> BytesRead(int64_t z0, int64_t count) const override {
    const int64_t slice = info_.dims.nx * info_.dims.ny * BytesPerVoxel(info_.dtype);
    return std::vector<FileRange>{{options_.header_bytes + z0 * slice, count * slice}};
  }

  absl::Status ReadSlices(int64_t z0, int64_t count, std::span<std::byte> out) override {
    const Dims& d = info_.dims;
    const int bpv = BytesPerVoxel(info_.dtype);
    const int64_t slice_bytes = d.nx * d.ny * bpv;
    SM_RETURN_IF_ERROR(CheckSliceRequest(z0, count, out.size()));
    SM_RETURN_IF_ERROR(AsInputError(
        ReadFullyAt(fd_.get(), options_.header_bytes + z0 * slice_bytes, out, info_.path)));
    if (NeedsSwap(options_.byte_order)) SwapBytes(out, bpv);
    return absl::OkStatus();
  }

 private:
  ScopedFd fd_;
  RawOptions options_;
};

class RawSink : public VolumeSink {
 public:
  RawSink(AtomicFileWriter writer, VolumeInfo info, ByteOrder order)
      : writer_(std::move(writer)), order_(order) {
    info_ = std::move(info);
  }

  absl::Status WriteSlices(int64_t count, std::span<const std::byte> data) override {
    SM_RETURN_IF_ERROR(Advance(count, data.size()));
    if (!NeedsSwap(order_)) return writer_.Append(data);
    std::vector<std::byte> swapped(data.begin(), data.end());
    SwapBytes(swapped, BytesPerVoxel(info_.dtype));
    return writer_.Append(swapped);
  }

  absl::Status Finish() override {
    SM_RETURN_IF_ERROR(CheckComplete());
    return writer_.Commit();
  }

 private:
  AtomicFileWriter writer_;
  ByteOrder order_;
};

}  // namespace

absl::StatusOr<std::unique_ptr<VolumeSource>> OpenRawVolume(const std::string& path,
                                                            const RawOptions& options,
                                                            const VolumeLimits& limits) {
  SM_RETURN_IF_ERROR(CheckDims(options.dims, options.dtype, limits, path));
  if (options.header_bytes < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": header_bytes ", options.header_bytes, " is negative"));
  }
  SM_ASSIGN_OR_RETURN(ScopedFd fd, OpenForRead(path));
  SM_ASSIGN_OR_RETURN(const int64_t size, FileSizeOf(fd.get(), path));
  const int64_t need = options.dims.num_voxels() * BytesPerVoxel(options.dtype);
  if (size != options.header_bytes + need) {
    const std::string header = options.header_bytes > 0
                                   ? absl::StrCat(" after a ", options.header_bytes, "-byte header")
                                   : std::string();
    return absl::InvalidArgumentError(absl::StrCat(
        path, ": dims ", options.dims.ToString(), " need ", need, " bytes of ",
        DTypeName(options.dtype), header, " (", options.header_bytes + need,
        " in all) but the file has ", size,
        size < options.header_bytes + need ? " (truncated?)" : " (wrong dims or dtype?)"));
  }
  VolumeInfo info;
  info.path = path;
  info.format = "raw";
  info.dims = options.dims;
  info.dtype = options.dtype;
  info.placement = options.placement;
  return std::make_unique<RawSource>(std::move(fd), options, std::move(info));
}

absl::StatusOr<std::unique_ptr<VolumeSink>> CreateRawWriter(const std::string& path,
                                                            const VolumeInfo& info,
                                                            ByteOrder byte_order) {
  SM_ASSIGN_OR_RETURN(AtomicFileWriter writer, AtomicFileWriter::Create(path));
  VolumeInfo out = info;
  out.path = path;
  out.format = "raw";
  return std::make_unique<RawSink>(std::move(writer), std::move(out), byte_order);
}

}  // namespace sheetmesh
