// NRRD volumes: attached (.nrrd) or detached (.nhdr + data file) headers, raw or gzip
// encoding, 3 dimensions of uint8, uint16 or float32.
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_NRRD_IO_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_NRRD_IO_H_

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "worker/pipeline/volume/volume_sink.h"
#include "worker/pipeline/volume/volume_source.h"

namespace sheetmesh {

enum class NrrdEncoding { kRaw, kGzip };

// A header longer than this is refused.
inline constexpr int64_t kNrrdMaxHeaderBytes = int64_t{1} << 20;

// The fields of a NRRD header that sheetmesh uses.
struct NrrdHeader {
  Dims dims;
  DType dtype = DType::kUInt8;
  ByteOrder byte_order = ByteOrder::kLittle;
  NrrdEncoding encoding = NrrdEncoding::kRaw;
  Placement placement;
  std::string data_file;     // empty: data follows the header in the same file
  int64_t byte_skip = 0;     // bytes skipped before the data (-1: data ends the file)
  int64_t line_skip = 0;     // lines skipped before the data (detached files)
  int64_t header_bytes = 0;  // size of the header including the blank line
};

// Parses a NRRD header from the start of `text` (which may continue with data). `path`
// names the file in messages. kInvalidArgument naming the field and value for a malformed
// or unsupported header (magic, dimension, type, encoding, sizes, spacing); kOutOfRange
// when `text` ends before the blank line that closes the header — unless `text` is the
// whole file and the header names a data file: a detached header may end with the file
// (teem and Slicer write them so), its last line with or without a newline.
absl::StatusOr<NrrdHeader> ParseNrrdHeader(absl::string_view text, absl::string_view path,
                                           const VolumeLimits& limits = {},
                                           bool text_is_whole_file = false);

// Opens a .nrrd or .nhdr volume.
absl::StatusOr<std::unique_ptr<VolumeSource>> OpenNrrdVolume(const std::string& path,
                                                             const VolumeLimits& limits = {});

// Writes an attached-header .nrrd in native byte order, raw or gzip.
absl::StatusOr<std::unique_ptr<VolumeSink>> CreateNrrdWriter(
    const std::string& path, const VolumeInfo& info, NrrdEncoding encoding = NrrdEncoding::kRaw);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_NRRD_IO_H_
