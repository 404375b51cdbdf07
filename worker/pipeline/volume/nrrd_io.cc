#include "worker/pipeline/volume/nrrd_io.h"

#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "common/file_util.h"
#include "common/paths.h"
#include "common/status_macros.h"

namespace sheetmesh {
namespace {

constexpr int64_t kMaxHeaderBytes = kNrrdMaxHeaderBytes;
constexpr int64_t kFirstHeaderRead = 1 << 16;

absl::Status FieldError(absl::string_view path, absl::string_view field, absl::string_view value,
                        absl::string_view why) {
  return absl::InvalidArgumentError(
      absl::StrCat(path, ": NRRD field '", field, "' = '", value, "' ", why));
}

absl::StatusOr<DType> ParseNrrdType(absl::string_view v, absl::string_view path) {
  const std::string t = absl::AsciiStrToLower(v);
  if (t == "uchar" || t == "unsigned char" || t == "uint8" || t == "uint8_t") return DType::kUInt8;
  if (t == "ushort" || t == "unsigned short" || t == "unsigned short int" || t == "uint16" ||
      t == "uint16_t") {
    return DType::kUInt16;
  }
  if (t == "float") return DType::kFloat32;
  return FieldError(path, "type", v, "is not supported; use uchar, ushort or float");
}

// Parses "(a,b,c)".
bool ParseVector(absl::string_view s, Vec3* out) {
  s = absl::StripAsciiWhitespace(s);
  if (s.size() < 2 || s.front() != '(' || s.back() != ')') return false;
  s = s.substr(1, s.size() - 2);
  std::vector<absl::string_view> parts = absl::StrSplit(s, ',');
  if (parts.size() != 3) return false;
  for (int k = 0; k < 3; ++k) {
    double v = 0;
    if (!absl::SimpleAtod(absl::StripAsciiWhitespace(parts[k]), &v) || !std::isfinite(v)) {
      return false;
    }
    (*out)[k] = v;
  }
  return true;
}

// The fields every header must have.
struct RequiredFields {
  bool dimension = false, type = false, sizes = false, encoding = false;
};

// The fields that say how the voxels are laid out: false when `key` is none of them.
absl::StatusOr<bool> ApplyLayoutField(const std::string& key, absl::string_view value,
                                      absl::string_view path, NrrdHeader* h, RequiredFields* seen) {
  if (key == "dimension") {
    int d = 0;
    if (!absl::SimpleAtoi(value, &d) || d != 3) {
      return FieldError(path, key, value, "is not supported; only 3-dimensional volumes");
    }
    seen->dimension = true;
  } else if (key == "type") {
    SM_ASSIGN_OR_RETURN(h->dtype, ParseNrrdType(value, path));
    seen->type = true;
  } else if (key == "sizes") {
    std::vector<absl::string_view> parts = absl::StrSplit(value, ' ', absl::SkipEmpty());
    int64_t n[3] = {0, 0, 0};
    if (parts.size() != 3 || !absl::SimpleAtoi(parts[0], &n[0]) ||
        !absl::SimpleAtoi(parts[1], &n[1]) || !absl::SimpleAtoi(parts[2], &n[2])) {
      return FieldError(path, key, value, "must be three integers");
    }
    h->dims = {n[0], n[1], n[2]};
    seen->sizes = true;
  } else if (key == "endian") {
    if (value != "little" && value != "big") {
      return FieldError(path, key, value, "must be little or big");
    }
    h->byte_order = value == "little" ? ByteOrder::kLittle : ByteOrder::kBig;
  } else if (key == "encoding") {
    if (value == "raw") {
      h->encoding = NrrdEncoding::kRaw;
    } else if (value == "gzip" || value == "gz") {
      h->encoding = NrrdEncoding::kGzip;
    } else {
      return FieldError(path, key, value, "is not supported; use raw or gzip");
    }
    seen->encoding = true;
  } else if (key == "data file" || key == "datafile") {
    if (absl::StartsWith(value, "LIST") || value.find('%') != absl::string_view::npos) {
      return FieldError(path, key, value, "lists several files; only one data file is supported");
    }
    h->data_file = std::string(value);
  } else if (key == "byte skip" || key == "byteskip") {
    if (!absl::SimpleAtoi(value, &h->byte_skip) || h->byte_skip < -1) {
      return FieldError(path, key, value, "must be an integer >= -1");
    }
  } else if (key == "line skip" || key == "lineskip") {
    if (!absl::SimpleAtoi(value, &h->line_skip) || h->line_skip < 0) {
      return FieldError(path, key, value, "must be an integer >= 0");
    }
  } else {
    return false;
  }
  return true;
}

// The fields that place the grid in space: false when `key` is none of them.
absl::StatusOr<bool> ApplyPlacementField(const std::string& key, absl::string_view value,
                                         absl::string_view path, Placement* p) {
  if (key == "spacings") {
    std::vector<absl::string_view> parts = absl::StrSplit(value, ' ', absl::SkipEmpty());
    if (parts.size() != 3) return FieldError(path, key, value, "must be three numbers");
    for (int k = 0; k < 3; ++k) {
      double v = 0;
      if (!absl::SimpleAtod(parts[k], &v) || !(v > 0) || !std::isfinite(v)) {
        return FieldError(path, key, value, "must be three positive numbers");
      }
      p->spacing[k] = v;
    }
  } else if (key == "space directions") {
    std::vector<absl::string_view> parts = absl::StrSplit(value, ' ', absl::SkipEmpty());
    if (parts.size() != 3) return FieldError(path, key, value, "must be three vectors");
    for (int k = 0; k < 3; ++k) {
      Vec3 v;
      if (!ParseVector(parts[k], &v)) {
        return FieldError(path, key, value, "must be three vectors like (1,0,0)");
      }
      // Axis-aligned grids only: the length of each direction is the spacing.
      const double len = Norm(v);
      if (!(len > 0)) return FieldError(path, key, value, "has a zero-length direction");
      if (std::abs(v[k]) < len * (1 - 1e-6)) {
        return FieldError(path, key, value, "is not axis-aligned; oblique grids are not supported");
      }
      p->spacing[k] = len;
    }
  } else if (key == "space origin") {
    if (!ParseVector(value, &p->origin)) {
      return FieldError(path, key, value, "must be a vector like (0,0,0)");
    }
  } else if (key == "space units") {
    std::vector<absl::string_view> parts = absl::StrSplit(value, ' ', absl::SkipEmpty());
    if (!parts.empty()) {
      p->unit = std::string(absl::StripPrefix(absl::StripSuffix(parts[0], "\""), "\""));
    }
  } else {
    return false;
  }
  return true;
}

absl::Status CheckRequired(const RequiredFields& seen, const NrrdHeader& h,
                           absl::string_view path) {
  for (const auto& [have, name] :
       {std::pair{seen.dimension, "dimension"}, std::pair{seen.type, "type"},
        std::pair{seen.sizes, "sizes"}, std::pair{seen.encoding, "encoding"}}) {
    if (!have) {
      return absl::InvalidArgumentError(absl::StrCat(path, ": NRRD header lacks '", name, "'"));
    }
  }
  if (h.byte_skip == -1 && h.encoding != NrrdEncoding::kRaw) {
    return FieldError(path, "byte skip", "-1", "is only valid with raw encoding");
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<NrrdHeader> ParseNrrdHeader(absl::string_view text, absl::string_view path,
                                           const VolumeLimits& limits, bool text_is_whole_file) {
  NrrdHeader h;
  if (text.size() < 8 || text.substr(0, 7) != "NRRD000" || !absl::ascii_isdigit(text[7])) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": not a NRRD file (it does not start with NRRD000x)"));
  }
  RequiredFields seen;
  size_t pos = text.find('\n') + 1;  // past the magic line
  bool closed = false;
  while (pos > 0 && pos < text.size() && pos < static_cast<size_t>(kMaxHeaderBytes)) {
    size_t nl = text.find('\n', pos);
    if (nl == absl::string_view::npos) {
      if (!text_is_whole_file) break;
      nl = text.size();  // the file's last line, without a newline
    }
    absl::string_view line = text.substr(pos, nl - pos);
    pos = std::min(nl + 1, text.size());
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.empty()) {
      closed = true;
      break;
    }
    // Comments, and "key:=value" pairs, which carry no field of ours.
    if (line[0] == '#' || line.find(":=") != absl::string_view::npos) continue;
    const size_t colon = line.find(": ");
    if (colon == absl::string_view::npos) {
      return absl::InvalidArgumentError(
          absl::StrCat(path, ": NRRD header line '", line.substr(0, 80), "' has no ': '"));
    }
    const std::string key = absl::AsciiStrToLower(line.substr(0, colon));
    const absl::string_view value = absl::StripAsciiWhitespace(line.substr(colon + 2));
    SM_ASSIGN_OR_RETURN(const bool layout, ApplyLayoutField(key, value, path, &h, &seen));
    if (!layout) SM_RETURN_IF_ERROR(ApplyPlacementField(key, value, path, &h.placement).status());
    // Other fields (kinds, labels, min, max, ...) do not change how voxels are read, and
    // unknown ones are tolerated, as the format asks of readers.
  }
  // A detached header that ends with its file needs no closing blank line.
  const bool ended_with_file = text_is_whole_file && pos >= text.size() && !h.data_file.empty();
  if (!closed && !ended_with_file) {
    if (pos >= static_cast<size_t>(kMaxHeaderBytes)) {
      return absl::InvalidArgumentError(
          absl::StrCat(path, ": NRRD header is longer than ", kMaxHeaderBytes, " bytes"));
    }
    return absl::OutOfRangeError(absl::StrCat(
        path, ": NRRD header has no closing blank line in its first ", text.size(), " bytes"));
  }
  SM_RETURN_IF_ERROR(CheckRequired(seen, h, path));
  SM_RETURN_IF_ERROR(CheckDims(h.dims, h.dtype, limits, path));
  h.header_bytes = static_cast<int64_t>(pos);
  return h;
}

namespace {

// Sequential gzip (or zlib) decoder over a byte range of a file.
class GzipStream {
 public:
  GzipStream(int fd, int64_t start, std::string path)
      : fd_(fd), start_(start), path_(std::move(path)), in_(1 << 16) {}
  ~GzipStream() {
    if (open_) inflateEnd(&zs_);
  }

  // Decodes exactly out.size() bytes. kInvalidArgument if the stream is corrupt or ends early.
  absl::Status Read(std::span<std::byte> out) {
    if (!open_) SM_RETURN_IF_ERROR(Reset());
    zs_.next_out = reinterpret_cast<Bytef*>(out.data());
    size_t remaining = out.size();
    while (remaining > 0) {
      const uInt chunk = static_cast<uInt>(std::min<size_t>(remaining, 1u << 30));
      zs_.next_out = reinterpret_cast<Bytef*>(out.data() + (out.size() - remaining));
      zs_.avail_out = chunk;
      while (zs_.avail_out > 0) {
        if (zs_.avail_in == 0) {
          const ssize_t n = ::pread(fd_, in_.data(), in_.size(), file_pos_);
          if (n < 0) return ErrnoStatus(errno, path_);
          if (n == 0) {
            return absl::InvalidArgumentError(absl::StrCat(path_, ": gzip data ends after ",
                                                           position_ + (chunk - zs_.avail_out),
                                                           " decoded bytes (truncated?)"));
          }
          file_pos_ += n;
          zs_.next_in = reinterpret_cast<Bytef*>(in_.data());
          zs_.avail_in = static_cast<uInt>(n);
        }
        const int rc = inflate(&zs_, Z_NO_FLUSH);
        if (rc == Z_STREAM_END && zs_.avail_out > 0) {
          return absl::InvalidArgumentError(
              absl::StrCat(path_, ": gzip stream ends after ", position_ + (chunk - zs_.avail_out),
                           " decoded bytes, fewer than the header's sizes need"));
        }
        if (rc != Z_OK && rc != Z_STREAM_END) {
          return absl::InvalidArgumentError(
              absl::StrCat(path_, ": corrupt gzip data (zlib: ", zs_.msg ? zs_.msg : "error", ")"));
        }
      }
      position_ += chunk;
      remaining -= chunk;
    }
    return absl::OkStatus();
  }

  // Discards `n` decoded bytes.
  absl::Status Skip(int64_t n) {
    std::vector<std::byte> scratch(std::min<int64_t>(n, 1 << 20));
    while (n > 0) {
      const int64_t k = std::min<int64_t>(n, scratch.size());
      SM_RETURN_IF_ERROR(Read(std::span<std::byte>(scratch.data(), k)));
      n -= k;
    }
    return absl::OkStatus();
  }

  absl::Status Reset() {
    if (open_) inflateEnd(&zs_);
    zs_ = {};
    // 15 + 32: accept both gzip and zlib wrappers.
    if (inflateInit2(&zs_, 15 + 32) != Z_OK) return absl::InternalError("inflateInit2 failed");
    open_ = true;
    file_pos_ = start_;
    position_ = 0;
    return absl::OkStatus();
  }

  int64_t position() const { return position_; }

 private:
  int fd_;
  int64_t start_;
  std::string path_;
  std::vector<std::byte> in_;
  z_stream zs_{};
  bool open_ = false;
  int64_t file_pos_ = 0;
  int64_t position_ = 0;  // decoded bytes delivered so far
};

class NrrdSource : public VolumeSource {
 public:
  NrrdSource(ScopedFd fd, NrrdHeader header, int64_t data_start, int64_t head_read, VolumeInfo info)
      : fd_(std::move(fd)),
        header_(std::move(header)),
        data_start_(data_start),
        head_read_(head_read) {
    info_ = std::move(info);
    if (header_.encoding == NrrdEncoding::kGzip) {
      gzip_ = std::make_unique<GzipStream>(fd_.get(), data_start_, info_.path);
    }
  }

  // Raw data attached: opening reads the header (what it read to parse it, and the lines it
  // skips), then the slices lie where they are.
  std::optional<std::vector<FileRange>> BytesRead(int64_t z0, int64_t count) const override {
    if (gzip_ != nullptr || !header_.data_file.empty()) return std::nullopt;
    const int64_t slice = info_.dims.nx * info_.dims.ny * BytesPerVoxel(info_.dtype);
    return std::vector<FileRange>{{0, std::max(data_start_, head_read_)},
                                  {data_start_ + z0 * slice, count * slice}};
  }

  absl::Status ReadSlices(int64_t z0, int64_t count, std::span<std::byte> out) override {
    const Dims& d = info_.dims;
    const int bpv = BytesPerVoxel(info_.dtype);
    const int64_t slice_bytes = d.nx * d.ny * bpv;
    SM_RETURN_IF_ERROR(CheckSliceRequest(z0, count, out.size()));
    if (gzip_ == nullptr) {
      SM_RETURN_IF_ERROR(
          AsInputError(ReadFullyAt(fd_.get(), data_start_ + z0 * slice_bytes, out, info_.path)));
    } else {
      const int64_t want = header_.byte_skip + z0 * slice_bytes;
      if (want < gzip_->position()) SM_RETURN_IF_ERROR(gzip_->Reset());
      SM_RETURN_IF_ERROR(gzip_->Skip(want - gzip_->position()));
      SM_RETURN_IF_ERROR(gzip_->Read(out));
    }
    if ((header_.byte_order == ByteOrder::kLittle) != NativeIsLittleEndian()) SwapBytes(out, bpv);
    return absl::OkStatus();
  }

 private:
  ScopedFd fd_;
  NrrdHeader header_;
  int64_t data_start_;
  int64_t head_read_;  // bytes of the file read to parse the header
  std::unique_ptr<GzipStream> gzip_;
};

// Offset after `lines` newline-terminated lines from `start`.
absl::StatusOr<int64_t> SkipLines(int fd, int64_t start, int64_t lines, const std::string& path) {
  int64_t pos = start;
  char buf[4096];
  while (lines > 0) {
    const ssize_t n = ::pread(fd, buf, sizeof(buf), pos);
    if (n < 0) return ErrnoStatus(errno, path);
    if (n == 0)
      return absl::InvalidArgumentError(absl::StrCat(path, ": file ends inside 'line skip'"));
    for (ssize_t i = 0; i < n && lines > 0; ++i) {
      ++pos;
      if (buf[i] == '\n') --lines;
    }
  }
  return pos;
}

class NrrdSink : public VolumeSink {
 public:
  NrrdSink(AtomicFileWriter writer, VolumeInfo info, NrrdEncoding encoding)
      : writer_(std::move(writer)), encoding_(encoding) {
    info_ = std::move(info);
  }
  ~NrrdSink() override {
    if (deflating_) deflateEnd(&zs_);
  }

  absl::Status Start() {
    const Placement& p = info_.placement;
    std::string header = absl::StrCat(
        "NRRD0004\n# written by sheetmesh\ntype: ",
        info_.dtype == DType::kUInt8 ? "uchar"
                                     : (info_.dtype == DType::kUInt16 ? "ushort" : "float"),
        "\ndimension: 3\nspace: right-anterior-superior\nsizes: ", info_.dims.nx, " ",
        info_.dims.ny, " ", info_.dims.nz, "\nspace directions: (", p.spacing.x, ",0,0) (0,",
        p.spacing.y, ",0) (0,0,", p.spacing.z, ")\nspace origin: (", p.origin.x, ",", p.origin.y,
        ",", p.origin.z,
        ")\nkinds: domain domain domain\nendian: ", NativeIsLittleEndian() ? "little" : "big",
        "\nencoding: ", encoding_ == NrrdEncoding::kGzip ? "gzip" : "raw", "\n");
    if (!p.unit.empty()) {
      absl::StrAppend(&header, "space units: \"", p.unit, "\" \"", p.unit, "\" \"", p.unit, "\"\n");
    }
    header += "\n";
    SM_RETURN_IF_ERROR(writer_.Append(header));
    if (encoding_ == NrrdEncoding::kGzip) {
      // 15 + 16: a gzip wrapper, as the NRRD format's "gzip" encoding means.
      if (deflateInit2(&zs_, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) {
        return absl::InternalError("deflateInit2 failed");
      }
      deflating_ = true;
    }
    return absl::OkStatus();
  }

  absl::Status WriteSlices(int64_t count, std::span<const std::byte> data) override {
    SM_RETURN_IF_ERROR(Advance(count, data.size()));
    if (encoding_ == NrrdEncoding::kRaw) return writer_.Append(data);
    return Deflate(data, Z_NO_FLUSH);
  }

  absl::Status Finish() override {
    SM_RETURN_IF_ERROR(CheckComplete());
    if (encoding_ == NrrdEncoding::kGzip) SM_RETURN_IF_ERROR(Deflate({}, Z_FINISH));
    return writer_.Commit();
  }

 private:
  absl::Status Deflate(std::span<const std::byte> data, int flush) {
    std::vector<std::byte> out(1 << 16);
    zs_.next_in = const_cast<Bytef*>(reinterpret_cast<const Bytef*>(data.data()));
    zs_.avail_in = static_cast<uInt>(data.size());
    int rc = Z_OK;
    do {
      zs_.next_out = reinterpret_cast<Bytef*>(out.data());
      zs_.avail_out = static_cast<uInt>(out.size());
      rc = deflate(&zs_, flush);
      if (rc == Z_STREAM_ERROR) return absl::InternalError("deflate failed");
      SM_RETURN_IF_ERROR(
          writer_.Append(std::span<const std::byte>(out.data(), out.size() - zs_.avail_out)));
    } while (zs_.avail_out == 0 || (flush == Z_FINISH && rc != Z_STREAM_END));
    return absl::OkStatus();
  }

  AtomicFileWriter writer_;
  NrrdEncoding encoding_;
  z_stream zs_{};
  bool deflating_ = false;
};

}  // namespace

absl::StatusOr<std::unique_ptr<VolumeSource>> OpenNrrdVolume(const std::string& path,
                                                             const VolumeLimits& limits) {
  SM_ASSIGN_OR_RETURN(ScopedFd fd, OpenForRead(path));
  SM_ASSIGN_OR_RETURN(const int64_t file_size, FileSizeOf(fd.get(), path));
  // The first 64 KiB hold any header but a freak's; then up to kMaxHeaderBytes. (What is read
  // is what a worker fetches of the file for a brick: BytesRead.)
  std::string head;
  absl::StatusOr<NrrdHeader> parsed;
  for (const int64_t want : {kFirstHeaderRead, kMaxHeaderBytes}) {
    head.assign(static_cast<size_t>(std::min(file_size, want)), '\0');
    SM_RETURN_IF_ERROR(AsInputError(
        ReadFullyAt(fd.get(), 0, std::as_writable_bytes(std::span<char>(head)), path)));
    const bool whole = file_size <= static_cast<int64_t>(head.size());
    parsed = ParseNrrdHeader(head, path, limits, /*text_is_whole_file=*/whole);
    if (!absl::IsOutOfRange(parsed.status()) || whole) break;
  }
  SM_ASSIGN_OR_RETURN(NrrdHeader h, std::move(parsed));
  const int64_t head_read = static_cast<int64_t>(head.size());

  ScopedFd data_fd;
  std::string data_path = path;
  int64_t start = h.header_bytes;
  if (!h.data_file.empty()) {
    std::filesystem::path p(h.data_file);
    if (p.is_relative()) p = std::filesystem::absolute(path).parent_path() / p;
    data_path = p.string();
    if (limits.confine_named_files) {
      // A header may name any file; the file must be one the caller may read.
      if (limits.named_file_roots.empty()) {
        return absl::PermissionDeniedError(absl::StrCat(
            path, ": the header's 'data file' names '", h.data_file,
            "'; a volume sent to the server may not name a file (send the data attached, or "
            "as a volume of several blobs)"));
      }
      SM_ASSIGN_OR_RETURN(data_path, ResolveUnderRoots(data_path, limits.named_file_roots,
                                                       absl::StrCat(path, ": data file")));
    }
    SM_ASSIGN_OR_RETURN(data_fd, OpenForRead(data_path));
    start = 0;
  } else {
    data_fd = std::move(fd);
  }
  SM_ASSIGN_OR_RETURN(start, SkipLines(data_fd.get(), start, h.line_skip, data_path));
  SM_ASSIGN_OR_RETURN(const int64_t data_size, FileSizeOf(data_fd.get(), data_path));
  const int64_t need = h.dims.num_voxels() * BytesPerVoxel(h.dtype);
  if (h.encoding == NrrdEncoding::kRaw) {
    if (h.byte_skip == -1) {
      start = data_size - need;
    } else {
      start += h.byte_skip;
    }
    if (start < 0 || data_size - start < need) {
      return absl::InvalidArgumentError(
          absl::StrCat(data_path, ": sizes ", h.dims.ToString(), " need ", need, " bytes of ",
                       DTypeName(h.dtype), " but the file holds ",
                       std::max<int64_t>(0, data_size - start), " after the header (truncated?)"));
    }
  }
  VolumeInfo info;
  info.path = path;
  info.format = "nrrd";
  info.dims = h.dims;
  info.dtype = h.dtype;
  info.placement = h.placement;
  return std::make_unique<NrrdSource>(std::move(data_fd), std::move(h), start, head_read,
                                      std::move(info));
}

absl::StatusOr<std::unique_ptr<VolumeSink>> CreateNrrdWriter(const std::string& path,
                                                             const VolumeInfo& info,
                                                             NrrdEncoding encoding) {
  SM_ASSIGN_OR_RETURN(AtomicFileWriter writer, AtomicFileWriter::Create(path));
  VolumeInfo out = info;
  out.path = path;
  out.format = "nrrd";
  auto sink = std::make_unique<NrrdSink>(std::move(writer), std::move(out), encoding);
  SM_RETURN_IF_ERROR(sink->Start());
  return sink;
}

}  // namespace sheetmesh
