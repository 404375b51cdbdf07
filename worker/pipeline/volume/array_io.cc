#include "worker/pipeline/volume/array_io.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <optional>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "common/byte_order.h"
#include "common/excerpt.h"
#include "common/file_util.h"
#include "common/status_macros.h"

namespace sheetmesh {
namespace {

// A voxel type as stored in the file.
enum class Stored { kU8, kI8, kU16, kI16, kU32, kI32, kF32, kF64 };

int StoredBytes(Stored s) {
  switch (s) {
    case Stored::kU8:
    case Stored::kI8:
      return 1;
    case Stored::kU16:
    case Stored::kI16:
      return 2;
    case Stored::kU32:
    case Stored::kI32:
    case Stored::kF32:
      return 4;
    case Stored::kF64:
      return 8;
  }
  return 1;
}

const char* StoredName(Stored s) {
  static const char* kNames[] = {"uint8",  "int8",  "uint16",  "int16",
                                 "uint32", "int32", "float32", "float64"};
  return kNames[static_cast<int>(s)];
}

// An array after a header, as a header reader found it.
struct StoredArray {
  std::string path, format;
  Dims dims;
  Stored type = Stored::kU8;
  ByteOrder order = ByteOrder::kLittle;
  int64_t offset = 0;
  double slope = 1, inter = 0;  // value = stored * slope + inter
  Placement placement;
};

template <class T>
T Load(const std::byte* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

// Converts `n` stored values of type T to float32 (value * slope + inter).
template <class T>
void ConvertRun(const std::byte* in, int64_t n, double slope, double inter, float* out) {
  for (int64_t i = 0; i < n; ++i) {
    out[i] = static_cast<float>(Load<T>(in + i * int64_t{sizeof(T)}) * slope + inter);
  }
}

// The type is chosen once per slice, not per voxel.
void Convert(Stored s, const std::byte* in, int64_t n, double slope, double inter, float* out) {
  switch (s) {
    case Stored::kU8:
      return ConvertRun<uint8_t>(in, n, slope, inter, out);
    case Stored::kI8:
      return ConvertRun<int8_t>(in, n, slope, inter, out);
    case Stored::kU16:
      return ConvertRun<uint16_t>(in, n, slope, inter, out);
    case Stored::kI16:
      return ConvertRun<int16_t>(in, n, slope, inter, out);
    case Stored::kU32:
      return ConvertRun<uint32_t>(in, n, slope, inter, out);
    case Stored::kI32:
      return ConvertRun<int32_t>(in, n, slope, inter, out);
    case Stored::kF32:
      return ConvertRun<float>(in, n, slope, inter, out);
    case Stored::kF64:
      return ConvertRun<double>(in, n, slope, inter, out);
  }
}

class ArraySource : public VolumeSource {
 public:
  ArraySource(ScopedFd fd, StoredArray a) : fd_(std::move(fd)), a_(std::move(a)) {
    info_.path = a_.path;
    info_.dims = a_.dims;
    info_.placement = a_.placement;
    const bool scaled = a_.slope != 1 || a_.inter != 0;
    if (!scaled && a_.type == Stored::kU8) {
      info_.dtype = DType::kUInt8;
    } else if (!scaled && a_.type == Stored::kU16) {
      info_.dtype = DType::kUInt16;
    } else {
      info_.dtype = DType::kFloat32;
      convert_ = scaled || a_.type != Stored::kF32;
    }
    info_.format =
        convert_ ? absl::StrCat(a_.format, " ", StoredName(a_.type), "→float32") : a_.format;
  }

  absl::Status ReadSlices(int64_t z0, int64_t count, std::span<std::byte> out) override {
    const Dims& d = info_.dims;
    const int64_t slice_voxels = d.nx * d.ny;
    const int width = StoredBytes(a_.type);
    SM_RETURN_IF_ERROR(CheckSliceRequest(z0, count, out.size()));
    const bool swap = (a_.order == ByteOrder::kLittle) != NativeIsLittleEndian();
    if (!convert_) {
      SM_RETURN_IF_ERROR(AsInputError(
          ReadFullyAt(fd_.get(), a_.offset + z0 * slice_voxels * width, out, info_.path)));
      if (swap && width > 1) SwapBytes(out, width);
      return absl::OkStatus();
    }
    // Converted a slice at a time: memory stays at one stored slice beside the output.
    buffer_.resize(static_cast<size_t>(slice_voxels * width));
    float* dst = reinterpret_cast<float*>(out.data());
    for (int64_t z = z0; z < z0 + count; ++z) {
      SM_RETURN_IF_ERROR(AsInputError(
          ReadFullyAt(fd_.get(), a_.offset + z * slice_voxels * width, buffer_, info_.path)));
      if (swap && width > 1) SwapBytes(buffer_, width);
      Convert(a_.type, buffer_.data(), slice_voxels, a_.slope, a_.inter, dst);
      dst += slice_voxels;
    }
    return absl::OkStatus();
  }

 private:
  ScopedFd fd_;
  StoredArray a_;
  bool convert_ = false;
  std::vector<std::byte> buffer_;
};

// Opens the array: dims within limits, the file long enough.
absl::StatusOr<std::unique_ptr<VolumeSource>> OpenArray(StoredArray a, const VolumeLimits& limits) {
  SM_RETURN_IF_ERROR(CheckDims(a.dims, DType::kFloat32, limits, a.path));
  SM_ASSIGN_OR_RETURN(ScopedFd fd, OpenForRead(a.path));
  SM_ASSIGN_OR_RETURN(const int64_t size, FileSizeOf(fd.get(), a.path));
  const int64_t need = a.dims.num_voxels() * StoredBytes(a.type);
  if (size < a.offset + need) {
    return absl::InvalidArgumentError(absl::StrCat(
        a.path, ": the header declares ", a.dims.ToString(), " ", StoredName(a.type), " (", need,
        " bytes from byte ", a.offset, ") but the file has ", size, " bytes (truncated?)"));
  }
  return std::make_unique<ArraySource>(std::move(fd), std::move(a));
}

absl::StatusOr<std::string> ReadHead(const std::string& path, int64_t bytes) {
  SM_ASSIGN_OR_RETURN(ScopedFd fd, OpenForRead(path));
  SM_ASSIGN_OR_RETURN(const int64_t size, FileSizeOf(fd.get(), path));
  std::string head(static_cast<size_t>(std::min(size, bytes)), '\0');
  SM_RETURN_IF_ERROR(ReadFullyAt(
      fd.get(), 0, std::span<std::byte>(reinterpret_cast<std::byte*>(head.data()), head.size()),
      path));
  return head;
}

absl::Status Bad(const std::string& path, absl::string_view field, absl::string_view what) {
  return absl::InvalidArgumentError(absl::StrCat(path, ": ", field, " ", what));
}

// The value of `key` in a .npy header dict ("'descr': '<u2', ..."), as text: a quoted
// string, True, False or a parenthesised tuple. A plain scan, linear in the header (a
// regular expression recursed once per character and overflowed the stack on a 40 KB
// shape).
std::optional<std::string> DictValue(absl::string_view dict, absl::string_view key) {
  const std::string quoted = absl::StrCat("'", key, "'");
  for (size_t at = dict.find(quoted); at != absl::string_view::npos;
       at = dict.find(quoted, at + 1)) {
    size_t i = at + quoted.size();
    auto skip_space = [&] {
      while (i < dict.size() && absl::ascii_isspace(static_cast<unsigned char>(dict[i]))) ++i;
    };
    skip_space();
    if (i >= dict.size() || dict[i] != ':') continue;
    ++i;
    skip_space();
    if (i >= dict.size()) return std::nullopt;
    const absl::string_view rest = dict.substr(i);
    if (rest[0] == '\'' || rest[0] == '(') {
      const size_t end = rest.find(rest[0] == '(' ? ')' : '\'', 1);
      if (end == absl::string_view::npos) return std::nullopt;
      return std::string(rest.substr(0, end + 1));
    }
    for (const char* word : {"True", "False"}) {
      if (absl::StartsWith(rest, word)) return std::string(word);
    }
    return std::nullopt;
  }
  return std::nullopt;
}

}  // namespace

absl::StatusOr<std::unique_ptr<VolumeSource>> OpenNpyVolume(const std::string& path,
                                                            const VolumeLimits& limits) {
  SM_ASSIGN_OR_RETURN(const std::string head, ReadHead(path, 65536 + 12));
  if (head.size() < 10 || head.compare(0, 6, "\x93NUMPY") != 0) {
    return Bad(path, "magic", "is not \\x93NUMPY: not a .npy file");
  }
  const int major = static_cast<uint8_t>(head[6]);
  int64_t header_len = 0, start = 0;
  if (major == 1) {
    header_len = static_cast<uint8_t>(head[8]) | (static_cast<uint8_t>(head[9]) << 8);
    start = 10;
  } else if (major == 2 || major == 3) {
    if (head.size() < 12) return Bad(path, "header", "is truncated");
    for (int k = 0; k < 4; ++k) header_len |= int64_t{static_cast<uint8_t>(head[8 + k])} << (8 * k);
    start = 12;
  } else {
    return Bad(path, "version", absl::StrCat(major, " is not 1, 2 or 3"));
  }
  if (start + header_len > static_cast<int64_t>(head.size())) {
    return Bad(path, "header", absl::StrCat("of ", header_len, " bytes is truncated"));
  }
  const std::string dict = head.substr(start, header_len);
  StoredArray a;
  a.path = path;
  a.format = "npy";
  a.offset = start + header_len;
  const auto descr = DictValue(dict, "descr");
  const auto fortran = DictValue(dict, "fortran_order");
  const auto shape = DictValue(dict, "shape");
  if (!descr || !fortran || !shape) {
    return Bad(path, "header",
               absl::StrCat("'", Excerpt(dict), "' lacks descr, fortran_order or shape"));
  }
  const std::string d = descr->substr(1, descr->size() - 2);  // without the quotes
  static const std::pair<const char*, Stored> kTypes[] = {
      {"u1", Stored::kU8},  {"i1", Stored::kI8},  {"b1", Stored::kU8},
      {"u2", Stored::kU16}, {"i2", Stored::kI16}, {"u4", Stored::kU32},
      {"i4", Stored::kI32}, {"f4", Stored::kF32}, {"f8", Stored::kF64}};
  bool found = false;
  if (d.size() == 3) {
    for (const auto& [code, type] : kTypes) {
      if (d.compare(1, 2, code) == 0) {
        a.type = type;
        found = true;
      }
    }
  }
  if (!found || (d[0] != '<' && d[0] != '>' && d[0] != '|' && d[0] != '=')) {
    return Bad(path, "descr",
               absl::StrCat("'", d,
                            "' is not a number type sheetmesh reads (u1 i1 b1 u2 i2 u4 i4 f4 f8)"));
  }
  a.order = d[0] == '>' ? ByteOrder::kBig : ByteOrder::kLittle;
  std::vector<int64_t> extents;
  for (absl::string_view p : absl::StrSplit(absl::StripPrefix(absl::StripSuffix(*shape, ")"), "("),
                                            ',', absl::SkipWhitespace())) {
    int64_t e = 0;
    if (!absl::SimpleAtoi(absl::StripAsciiWhitespace(p), &e) || e <= 0) {
      return Bad(
          path, "shape",
          absl::StrCat(Excerpt(*shape), " has a bad extent '", Excerpt(std::string(p)), "'"));
    }
    extents.push_back(e);
  }
  if (extents.size() != 2 && extents.size() != 3) {
    return Bad(path, "shape", absl::StrCat(Excerpt(*shape), " is not 2D or 3D"));
  }
  const bool f_order = *fortran == "True";
  // C order lists the slowest axis first: (z, y, x) or (y, x); Fortran order the fastest.
  if (extents.size() == 2) extents.insert(f_order ? extents.end() : extents.begin(), 1);
  a.dims =
      f_order ? Dims{extents[0], extents[1], extents[2]} : Dims{extents[2], extents[1], extents[0]};
  return OpenArray(std::move(a), limits);
}

absl::StatusOr<std::unique_ptr<VolumeSource>> OpenMrcVolume(const std::string& path,
                                                            const VolumeLimits& limits) {
  SM_ASSIGN_OR_RETURN(const std::string head, ReadHead(path, 1024));
  if (head.size() < 1024) return Bad(path, "header", "is shorter than MRC's 1024 bytes");
  // The machine stamp (word 54) gives the byte order; files without one are read as
  // little-endian when their dims make sense that way.
  const auto* b = reinterpret_cast<const std::byte*>(head.data());
  const uint8_t stamp = static_cast<uint8_t>(head[212]);
  ByteOrder order = stamp == 0x11 ? ByteOrder::kBig : ByteOrder::kLittle;
  const bool swap = (order == ByteOrder::kLittle) != NativeIsLittleEndian();
  auto word = [&](int i) {
    std::array<std::byte, 4> w;
    std::memcpy(w.data(), b + 4 * i, 4);
    if (swap) std::reverse(w.begin(), w.end());
    return w;
  };
  auto i32 = [&](int i) { return Load<int32_t>(word(i).data()); };
  auto f32 = [&](int i) { return Load<float>(word(i).data()); };
  StoredArray a;
  a.path = path;
  a.format = "mrc";
  a.order = order;
  a.dims = {i32(0), i32(1), i32(2)};
  if (a.dims.nx <= 0 || a.dims.ny <= 0 || a.dims.nz <= 0) {
    return Bad(path, "NX, NY, NZ",
               absl::StrCat(a.dims.nx, " ", a.dims.ny, " ", a.dims.nz,
                            " are not positive (not an MRC file?)"));
  }
  const int mode = i32(3);
  switch (mode) {
    case 0:
      a.type = Stored::kI8;
      break;
    case 1:
      a.type = Stored::kI16;
      break;
    case 2:
      a.type = Stored::kF32;
      break;
    case 6:
      a.type = Stored::kU16;
      break;
    default:
      return Bad(path, "MODE",
                 absl::StrCat(mode,
                              " is not read (0 int8, 1 int16, 2 float32, 6 uint16; complex and "
                              "float16 modes are not)"));
  }
  if (i32(16) != 1 || i32(17) != 2 || i32(18) != 3) {
    return Bad(path, "MAPC, MAPR, MAPS",
               absl::StrCat(i32(16), " ", i32(17), " ", i32(18),
                            " are not 1 2 3: reorder the axes to x, y, z first"));
  }
  const int32_t ext = i32(23);
  if (ext < 0) return Bad(path, "NSYMBT", absl::StrCat(ext, " is negative"));
  a.offset = 1024 + int64_t{ext};
  const int32_t m[3] = {i32(7), i32(8), i32(9)};
  const float cell[3] = {f32(10), f32(11), f32(12)};
  for (int k = 0; k < 3; ++k) {
    if (m[k] > 0 && cell[k] > 0 && std::isfinite(cell[k])) a.placement.spacing[k] = cell[k] / m[k];
  }
  a.placement.unit = "angstrom";
  const float origin[3] = {f32(49), f32(50), f32(51)};
  const bool has_origin = std::isfinite(origin[0]) && std::isfinite(origin[1]) &&
                          std::isfinite(origin[2]) &&
                          (origin[0] != 0 || origin[1] != 0 || origin[2] != 0);
  for (int k = 0; k < 3; ++k) {
    a.placement.origin[k] = has_origin ? origin[k] : i32(4 + k) * a.placement.spacing[k];
  }
  return OpenArray(std::move(a), limits);
}

absl::StatusOr<std::unique_ptr<VolumeSource>> OpenNiftiVolume(const std::string& path,
                                                              const VolumeLimits& limits) {
  SM_ASSIGN_OR_RETURN(const std::string head, ReadHead(path, 352));
  if (head.size() >= 2 && static_cast<uint8_t>(head[0]) == 0x1f &&
      static_cast<uint8_t>(head[1]) == 0x8b) {
    return Bad(path, "encoding", "is gzip (.nii.gz): gunzip it to a .nii first");
  }
  if (head.size() < 348) return Bad(path, "header", "is shorter than NIfTI-1's 348 bytes");
  const auto* b = reinterpret_cast<const std::byte*>(head.data());
  int32_t sizeof_hdr = Load<int32_t>(b);
  bool swap = false;
  if (sizeof_hdr != 348) {
    std::byte w[4];
    std::memcpy(w, b, 4);
    std::reverse(w, w + 4);
    sizeof_hdr = Load<int32_t>(w);
    swap = true;
  }
  if (sizeof_hdr == 540) return Bad(path, "sizeof_hdr", "540 is NIfTI-2, which is not read");
  if (sizeof_hdr != 348) {
    return Bad(path, "sizeof_hdr", "is not 348 in either byte order: not a NIfTI-1 file");
  }
  const std::string magic = head.substr(344, 3);
  if (magic == "ni1") {
    return Bad(path, "magic", "'ni1' is a .hdr/.img pair: give the .img as raw with its dims");
  }
  if (magic != "n+1") return Bad(path, "magic", absl::StrCat("'", magic, "' is not 'n+1'"));
  auto get = [&](int offset, int width) {
    std::array<std::byte, 8> w{};
    std::memcpy(w.data(), b + offset, width);
    if (swap) std::reverse(w.begin(), w.begin() + width);
    return w;
  };
  auto i16 = [&](int o) { return Load<int16_t>(get(o, 2).data()); };
  auto f32 = [&](int o) { return Load<float>(get(o, 4).data()); };
  StoredArray a;
  a.path = path;
  a.format = "nifti";
  a.order = swap == NativeIsLittleEndian() ? ByteOrder::kBig : ByteOrder::kLittle;
  const int ndim = i16(40);
  if (ndim < 2 || ndim > 7) return Bad(path, "dim[0]", absl::StrCat(ndim, " is not 2 to 7"));
  a.dims = {i16(42), i16(44), ndim >= 3 ? i16(46) : int64_t{1}};
  for (int k = 4; k <= ndim; ++k) {
    if (i16(40 + 2 * k) > 1) {
      return Bad(path, absl::StrCat("dim[", k, "]"),
                 absl::StrCat(i16(40 + 2 * k), ": only one 3D volume is read (no time series)"));
    }
  }
  if (a.dims.nx <= 0 || a.dims.ny <= 0 || a.dims.nz <= 0) {
    return Bad(path, "dim", absl::StrCat(a.dims.ToString(), " is not positive"));
  }
  const int datatype = i16(70);
  static const std::pair<int, Stored> kTypes[] = {
      {2, Stored::kU8},   {4, Stored::kI16},  {8, Stored::kI32},   {16, Stored::kF32},
      {64, Stored::kF64}, {256, Stored::kI8}, {512, Stored::kU16}, {768, Stored::kU32}};
  bool found = false;
  for (const auto& [code, type] : kTypes) {
    if (code == datatype) {
      a.type = type;
      found = true;
    }
  }
  if (!found) {
    return Bad(path, "datatype",
               absl::StrCat(datatype, " is not read (2, 4, 8, 16, 64, 256, 512, 768)"));
  }
  for (int k = 0; k < 3; ++k) {
    const float p = std::abs(f32(80 + 4 * k));
    if (p > 0 && std::isfinite(p)) a.placement.spacing[k] = p;
  }
  const float vox_offset = f32(108);
  a.offset = std::max<int64_t>(352, static_cast<int64_t>(vox_offset));
  const float slope = f32(112), inter = f32(116);
  if (slope != 0 && std::isfinite(slope) && std::isfinite(inter)) {
    a.slope = slope;
    a.inter = inter;
  }
  const int units = static_cast<uint8_t>(head[123]) & 7;
  a.placement.unit = units == 1 ? "m" : units == 2 ? "mm" : units == 3 ? "um" : "";
  // The translation of the sform (or the qform offsets); rotations are not applied.
  if (i16(254) > 0) {
    a.placement.origin = {f32(280 + 12), f32(296 + 12), f32(312 + 12)};
  } else if (i16(252) > 0) {
    a.placement.origin = {f32(268), f32(272), f32(276)};
  }
  return OpenArray(std::move(a), limits);
}

}  // namespace sheetmesh
