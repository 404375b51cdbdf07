// DICOM slices through GDCM: one image per file (a CT or micro-CT series), any transfer
// syntax GDCM decodes. Headers are read up to the pixel data; values are the stored ones
// times RescaleSlope plus RescaleIntercept (Hounsfield units for CT), as float32 unless
// the stored type is unsigned 8- or 16-bit and the rescale is the identity.
#include <gdcmImage.h>
#include <gdcmImageReader.h>
#include <gdcmReader.h>
#include <gdcmStringFilter.h>
#include <gdcmTrace.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <span>
#include <filesystem>
#include <fstream>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "absl/strings/str_format.h"
#include "common/file_util.h"
#include "common/status_macros.h"
#include "worker/pipeline/volume/slice_stack.h"

namespace sheetmesh {
namespace {

const gdcm::Tag kRows(0x0028, 0x0010);
const gdcm::Tag kColumns(0x0028, 0x0011);
const gdcm::Tag kSamplesPerPixel(0x0028, 0x0002);
const gdcm::Tag kBitsAllocated(0x0028, 0x0100);
const gdcm::Tag kPixelRepresentation(0x0028, 0x0103);
const gdcm::Tag kNumberOfFrames(0x0028, 0x0008);
const gdcm::Tag kPixelSpacing(0x0028, 0x0030);
const gdcm::Tag kRescaleIntercept(0x0028, 0x1052);
const gdcm::Tag kRescaleSlope(0x0028, 0x1053);
const gdcm::Tag kImagePosition(0x0020, 0x0032);
const gdcm::Tag kImageOrientation(0x0020, 0x0037);
const gdcm::Tag kSeriesInstanceUid(0x0020, 0x000e);
const gdcm::Tag kInstanceNumber(0x0020, 0x0013);
const gdcm::Tag kPixelData(0x7fe0, 0x0010);

// The numbers of a multi-valued DICOM string ("0.5\0.5"); nullopt when absent or when
// there are not `count` of them.
std::optional<std::vector<double>> Numbers(const gdcm::StringFilter& sf, const gdcm::DataSet& ds,
                                           const gdcm::Tag& tag, size_t count) {
  if (!ds.FindDataElement(tag) || ds.GetDataElement(tag).IsEmpty()) return std::nullopt;
  std::vector<double> out;
  for (absl::string_view part : absl::StrSplit(sf.ToString(tag), '\\')) {
    double v = 0;
    if (!absl::SimpleAtod(absl::StripAsciiWhitespace(part), &v)) return std::nullopt;
    out.push_back(v);
  }
  if (out.size() != count) return std::nullopt;
  return out;
}

struct StoredFormat {
  uint32_t width = 0, height = 0;
  int bits = 0;
  bool is_signed = false;
  double slope = 1, intercept = 0;
};

std::string Kind(const StoredFormat& f) {
  std::string k = absl::StrCat(f.is_signed ? "int" : "uint", f.bits);
  if (f.slope != 1 || f.intercept != 0) absl::StrAppend(&k, " rescaled");
  return k;
}

DType NativeType(const StoredFormat& f) {
  if (f.slope == 1 && f.intercept == 0 && !f.is_signed) {
    if (f.bits == 8) return DType::kUInt8;
    if (f.bits == 16) return DType::kUInt16;
  }
  return DType::kFloat32;
}

// GDCM prints its warnings and errors to stderr; the reader reports through its statuses.
void QuietGdcm() {
  static const bool once = [] {
    gdcm::Trace::SetWarning(false);
    gdcm::Trace::SetError(false);
    gdcm::Trace::SetDebug(false);
    return true;
  }();
  (void)once;
}

// Reads and checks the fields that say how the pixels are stored.
// Walks a Part 10 file's elements before GDCM reads it: GDCM 3.0 asserts, aborting the
// process, on elements whose VR or length is damaged (in the meta group, and in the data set
// through its fallback reader). Each element's VR must be one the standard names, its value
// must lie in the file (or the item holding it), the meta group's tags must ascend and its
// length (0002,0000) say where it ends, sequences and items must close, nesting at most
// kMaxDepth deep. A file without the preamble, or in the deflated syntax, is walked as far as
// its meta group (GDCM is left the rest; a job's child or the CLI's child reader contains it).
class DicomWalk {
 public:
  DicomWalk(const std::string& file, std::vector<unsigned char> bytes)
      : file_(file), b_(std::move(bytes)) {}

  absl::Status Check() {
    if (b_.size() < 132 || std::memcmp(b_.data() + 128, "DICM", 4) != 0) return absl::OkStatus();
    size_t at = 132;
    int64_t group_end = -1;
    uint32_t last = 0;
    std::string syntax;
    while (at + 8 <= b_.size() && U16(at) == 0x0002) {
      const size_t start = at;
      const uint32_t tag = U32(at);
      if (tag <= last && at > 132) return Bad(at, "the meta group's elements are out of order");
      last = tag;
      size_t length = 0;
      std::string vr;
      SM_RETURN_IF_ERROR(Element(&at, b_.size(), /*explicit_vr=*/true, &vr, &length));
      if (length == kUndefined) return Bad(start, "a meta element of undefined length");
      if (tag == 0x00000002 && vr == "UL" && length == 4) group_end = at + 4 + U32(at);
      if (tag == 0x00100002) {
        syntax.assign(reinterpret_cast<const char*>(b_.data() + at), length);
        while (!syntax.empty() && (syntax.back() == '\0' || syntax.back() == ' ')) syntax.pop_back();
      }
      at += length;
    }
    if (group_end >= 0 && group_end != static_cast<int64_t>(at)) {
      return Bad(132, absl::StrCat("its meta group's length (0002,0000) says it ends at byte ",
                                   group_end, " but its elements end at byte ", at));
    }
    if (syntax.empty()) return Bad(132, "its meta group names no transfer syntax (0002,0010)");
    if (syntax == "1.2.840.10008.1.2.1.99") return absl::OkStatus();  // deflated
    big_ = syntax == "1.2.840.10008.1.2.2";
    return DataSet(&at, b_.size(), syntax != "1.2.840.10008.1.2", 0, /*until_item_end=*/false);
  }

 private:
  static constexpr size_t kUndefined = 0xFFFFFFFFu;
  static constexpr int kMaxDepth = 16;

  uint32_t U16(size_t at) const {
    return big_ ? uint32_t{b_[at]} << 8 | b_[at + 1] : uint32_t{b_[at]} | uint32_t{b_[at + 1]} << 8;
  }
  uint32_t U32(size_t at) const {
    return big_ ? U16(at) << 16 | U16(at + 2) : U16(at) | U16(at + 2) << 16;
  }
  // A tag as (group << 16 | element), whatever the byte order.
  uint32_t Tag(size_t at) const { return U16(at) << 16 | U16(at + 2); }

  absl::Status Bad(size_t at, absl::string_view what) const {
    return absl::InvalidArgumentError(
        absl::StrCat(file_, ": not a readable DICOM file: at byte ", at, ": ", what));
  }

  // Reads an element's header at *at (within `end`): its VR (explicit) and value length;
  // leaves *at at its value. A defined length must fit before `end`.
  absl::Status Element(size_t* at, size_t end, bool explicit_vr, std::string* vr, size_t* length) {
    static const absl::flat_hash_set<std::string> kVrs = {
        "AE", "AS", "AT", "CS", "DA", "DS", "DT", "FL", "FD", "IS", "LO", "LT", "OB", "OD", "OF",
        "OL", "OV", "OW", "PN", "SH", "SL", "SQ", "SS", "ST", "SV", "TM", "UC", "UI", "UL", "UN",
        "UR", "US", "UT", "UV"};
    static const absl::flat_hash_set<std::string> kLong = {"OB", "OD", "OF", "OL", "OV", "OW", "SQ",
                                                           "SV", "UC", "UN", "UR", "UT", "UV"};
    const size_t start = *at;
    const uint32_t tag = Tag(start);
    size_t header = 8;
    vr->clear();
    if (explicit_vr && tag >> 16 != 0xFFFE) {
      if (start + 8 > end) return Bad(start, "the data ends within an element");
      vr->assign(reinterpret_cast<const char*>(b_.data() + start + 4), 2);
      if (!kVrs.contains(*vr)) {
        return Bad(start, absl::StrFormat("element (%04X,%04X)'s value representation is not one "
                                          "DICOM names",
                                          tag >> 16, tag & 0xFFFF));
      }
      header = kLong.contains(*vr) ? 12 : 8;
    }
    if (start + header > end) return Bad(start, "the data ends within an element");
    *length = header == 12 || !explicit_vr || tag >> 16 == 0xFFFE ? U32(start + header - 4)
                                                                  : U16(start + 6);
    *at = start + header;
    if (*length != kUndefined && *length > end - *at) {
      return Bad(start, absl::StrFormat("element (%04X,%04X) declares %d bytes, past the end of "
                                        "what holds it",
                                        tag >> 16, tag & 0xFFFF, *length));
    }
    return absl::OkStatus();
  }

  // The elements GDCM reads as typed attributes to make an image must carry the VR the
  // standard gives them (GDCM asserts, aborting, on another), and a UID only digits and
  // dots (a damaged SOP class sends GDCM down its ACR-NEMA path, which asserts too).
  absl::Status Typed(size_t start, uint32_t tag, const std::string& vr, size_t value,
                     size_t length) const {
    static const absl::flat_hash_map<uint32_t, const char*> kImageVrs = {
        {0x00280002, "US"}, {0x00280004, "CS"}, {0x00280006, "US"}, {0x00280008, "IS"},
        {0x00280010, "US"}, {0x00280011, "US"}, {0x00280030, "DS"}, {0x00280100, "US"},
        {0x00280101, "US"}, {0x00280102, "US"}, {0x00280103, "US"}, {0x00281050, "DS"},
        {0x00281051, "DS"}, {0x00281052, "DS"}, {0x00281053, "DS"}, {0x00200032, "DS"},
        {0x00200037, "DS"}, {0x00200013, "IS"}, {0x00180050, "DS"}, {0x00180088, "DS"},
        {0x00080010, "SH"}};
    if (!vr.empty()) {
      const auto it = kImageVrs.find(tag);
      if (it != kImageVrs.end() && vr != it->second) {
        return Bad(start, absl::StrFormat("element (%04X,%04X) has value representation %s where "
                                          "DICOM gives %s",
                                          tag >> 16, tag & 0xFFFF, vr, it->second));
      }
    }
    // A recognition code sends GDCM down its ACR-NEMA path, which asserts unless it is one.
    if (tag == 0x00080010 && length != kUndefined) {
      const std::string code(reinterpret_cast<const char*>(b_.data() + value), length);
      if (!absl::StartsWith(code, "ACR-NEMA") && !absl::StartsWith(code, "ACRNEMA") &&
          !absl::StartsWith(code, "MIPS 2.0")) {
        return Bad(start, "its recognition code (0008,0010) names no ACR-NEMA version");
      }
    }
    const bool uid = vr == "UI" || (vr.empty() && (tag == 0x00080016 || tag == 0x00080018 ||
                                                    tag == 0x0020000D || tag == 0x0020000E));
    if (uid && length != kUndefined) {
      for (size_t k = 0; k < length; ++k) {
        const unsigned char c = b_[value + k];
        const bool pad = c == 0 || c == ' ';
        if (!(std::isdigit(c) || c == '.' || (pad && k + 1 == length))) {
          return Bad(start, absl::StrFormat("element (%04X,%04X), a UID, holds a character other "
                                            "than digits and dots",
                                            tag >> 16, tag & 0xFFFF));
        }
      }
    }
    return absl::OkStatus();
  }

  // Elements from *at to `end`, or (until_item_end) to an item delimiter.
  absl::Status DataSet(size_t* at, size_t end, bool explicit_vr, int depth, bool until_item_end) {
    if (depth > kMaxDepth) return Bad(*at, "sequences nested too deep");
    while (*at < end) {
      const size_t start = *at;
      if (start + 8 > end) return Bad(start, "the data ends within an element");
      const uint32_t tag = Tag(start);
      if (tag == 0xFFFEE00D) {  // an item ends
        if (!until_item_end) return Bad(start, "an item's end outside an item");
        *at = start + 8;
        return absl::OkStatus();
      }
      std::string vr;
      size_t length = 0;
      SM_RETURN_IF_ERROR(Element(at, end, explicit_vr, &vr, &length));
      if (tag >> 16 == 0xFFFE) return Bad(start, "an item or sequence mark among elements");
      if (depth == 0) SM_RETURN_IF_ERROR(Typed(start, tag, vr, *at, length));
      const bool sequence = vr == "SQ" || (length == kUndefined && vr != "OB" && vr != "OW" &&
                                           tag != 0x7FE00010);
      if (sequence) {
        SM_RETURN_IF_ERROR(Items(at, length == kUndefined ? end : *at + length, explicit_vr,
                                 depth + 1, length == kUndefined));
      } else if (length == kUndefined) {  // encapsulated pixel data: fragments, then the end
        SM_RETURN_IF_ERROR(Items(at, end, explicit_vr, kMaxDepth, /*until_end=*/true));
      } else {
        *at += length;
      }
    }
    if (until_item_end) return Bad(*at, "an item of undefined length is never closed");
    return absl::OkStatus();
  }

  // The items of a sequence from *at to `end`, or (until_end) to a sequence delimiter.
  // At kMaxDepth, items are fragments: not parsed.
  absl::Status Items(size_t* at, size_t end, bool explicit_vr, int depth, bool until_end) {
    while (*at < end) {
      const size_t start = *at;
      if (start + 8 > end) return Bad(start, "the data ends within a sequence");
      const uint32_t tag = Tag(start);
      const size_t length = U32(start + 4);
      *at = start + 8;
      if (tag == 0xFFFEE0DD) {
        if (!until_end || length != 0) return Bad(start, "a stray sequence end");
        return absl::OkStatus();
      }
      if (tag != 0xFFFEE000) return Bad(start, "a sequence holds something other than items");
      if (length == kUndefined) {
        if (depth >= kMaxDepth) return Bad(start, "a fragment of undefined length");
        SM_RETURN_IF_ERROR(DataSet(at, end, explicit_vr, depth, /*until_item_end=*/true));
      } else if (length > end - *at) {
        return Bad(start, absl::StrCat("an item declares ", length, " bytes, past its sequence"));
      } else if (depth < kMaxDepth) {
        SM_RETURN_IF_ERROR(DataSet(at, *at + length, explicit_vr, depth, false));
      } else {
        *at += length;
      }
    }
    if (until_end) return Bad(*at, "a sequence of undefined length is never closed");
    return absl::OkStatus();
  }

  const std::string& file_;
  std::vector<unsigned char> b_;
  bool big_ = false;
};

absl::Status CheckFileMeta(const std::string& file) {
  SM_ASSIGN_OR_RETURN(ScopedFd fd, OpenForRead(file));
  SM_ASSIGN_OR_RETURN(const int64_t size, FileSizeOf(fd.get(), file));
  // A slice beyond 256 MiB is walked as far as its first 256 MiB say (GDCM reads the rest).
  std::vector<unsigned char> b(static_cast<size_t>(std::min<int64_t>(size, int64_t{256} << 20)));
  SM_RETURN_IF_ERROR(
      AsInputError(ReadFullyAt(fd.get(), 0, std::as_writable_bytes(std::span(b)), file)));
  const bool whole = static_cast<int64_t>(b.size()) == size;
  absl::Status status = DicomWalk(file, std::move(b)).Check();
  return whole || status.ok() || !absl::StrContains(status.message(), "past the end") ? status
                                                                                    : absl::OkStatus();
}

absl::StatusOr<StoredFormat> ReadStoredFormat(const std::string& file, const gdcm::File& f) {
  gdcm::StringFilter sf;
  sf.SetFile(f);
  const gdcm::DataSet& ds = f.GetDataSet();
  auto number = [&](const gdcm::Tag& tag, const char* field,
                    std::optional<double> fallback) -> absl::StatusOr<double> {
    std::optional<std::vector<double>> v = Numbers(sf, ds, tag, 1);
    if (v) return (*v)[0];
    if (fallback) return *fallback;
    return absl::InvalidArgumentError(
        absl::StrCat(file, ": DICOM field ", field, " is missing or not a number"));
  };
  StoredFormat s;
  SM_ASSIGN_OR_RETURN(const double rows, number(kRows, "Rows (0028,0010)", std::nullopt));
  SM_ASSIGN_OR_RETURN(const double cols, number(kColumns, "Columns (0028,0011)", std::nullopt));
  SM_ASSIGN_OR_RETURN(const double spp, number(kSamplesPerPixel, "SamplesPerPixel", 1.0));
  SM_ASSIGN_OR_RETURN(const double bits,
                      number(kBitsAllocated, "BitsAllocated (0028,0100)", std::nullopt));
  SM_ASSIGN_OR_RETURN(const double repr, number(kPixelRepresentation, "PixelRepresentation", 0.0));
  SM_ASSIGN_OR_RETURN(const double frames, number(kNumberOfFrames, "NumberOfFrames", 1.0));
  SM_ASSIGN_OR_RETURN(s.slope, number(kRescaleSlope, "RescaleSlope", 1.0));
  SM_ASSIGN_OR_RETURN(s.intercept, number(kRescaleIntercept, "RescaleIntercept", 0.0));
  if (!(rows >= 1 && cols >= 1 && rows <= 1 << 20 && cols <= 1 << 20)) {
    return absl::InvalidArgumentError(
        absl::StrCat(file, ": DICOM image of ", cols, "x", rows, " (Columns x Rows)"));
  }
  if (spp != 1) {
    return absl::InvalidArgumentError(absl::StrCat(file, ": DICOM SamplesPerPixel ", spp,
                                                   "; only single-channel (grey) images are read"));
  }
  if (frames != 1) {
    return absl::InvalidArgumentError(
        absl::StrCat(file, ": multi-frame DICOM (NumberOfFrames ", frames,
                     ") is not read; export the series as one file per slice"));
  }
  if (bits != 8 && bits != 16 && bits != 32) {
    return absl::InvalidArgumentError(
        absl::StrCat(file, ": DICOM BitsAllocated ", bits, " (8, 16 or 32 are read)"));
  }
  if (!(s.slope != 0 && std::isfinite(s.slope) && std::isfinite(s.intercept))) {
    return absl::InvalidArgumentError(
        absl::StrCat(file, ": DICOM RescaleSlope ", s.slope, " / RescaleIntercept ", s.intercept));
  }
  s.width = static_cast<uint32_t>(cols);
  s.height = static_cast<uint32_t>(rows);
  s.bits = static_cast<int>(bits);
  s.is_signed = repr == 1;
  return s;
}

template <typename T>
void Rescale(const char* in, size_t n, double slope, double intercept, float* out) {
  for (size_t i = 0; i < n; ++i) {
    T v;
    std::memcpy(&v, in + i * sizeof(T), sizeof(T));
    out[i] = static_cast<float>(static_cast<double>(v) * slope + intercept);
  }
}

class DicomSliceCodec : public SliceCodec {
 public:
  std::string name() const override { return "dicom"; }

  bool Claims(const std::string& file) const override {
    const std::string ext = absl::AsciiStrToLower(std::filesystem::path(file).extension().string());
    if (ext == ".dcm" || ext == ".dicom" || ext == ".dic" || ext == ".ima") return true;
    // Series often come as files without an extension: the Part 10 preamble says.
    char head[132];
    std::ifstream in(file, std::ios::binary);
    return in.read(head, sizeof(head)) && std::memcmp(head + 128, "DICM", 4) == 0;
  }

  absl::StatusOr<SliceHeader> ReadHeader(const std::string& file,
                                         const VolumeLimits& limits) const override {
    SM_RETURN_IF_ERROR(CheckFileMeta(file));
    QuietGdcm();
    gdcm::Reader reader;
    reader.SetFileName(file.c_str());
    // Skipping the pixel data leaves the stream where its value starts.
    if (!reader.ReadUpToTag(kPixelData, {kPixelData})) {
      return absl::InvalidArgumentError(absl::StrCat(file, ": not a readable DICOM file"));
    }
    const gdcm::File& f = reader.GetFile();
    SM_ASSIGN_OR_RETURN(StoredFormat s, ReadStoredFormat(file, f));
    // Uncompressed pixels lie from there on: a file cut short in them would read (GDCM
    // fills the rest with zeros), so it is measured here.
    const gdcm::TransferSyntax& ts = f.GetHeader().GetDataSetTransferSyntax();
    if (!ts.IsEncapsulated()) {
      std::error_code ec;
      const uint64_t size = std::filesystem::file_size(file, ec);
      const uint64_t need =
          reader.GetStreamCurrentPosition() + uint64_t{s.width} * s.height * (s.bits / 8);
      if (!ec && size < need) {
        return absl::InvalidArgumentError(absl::StrCat(
            file, ": DICOM file has ", size, " bytes but its PixelData (7FE0,0010) for ", s.width,
            "x", s.height, " pixels of ", s.bits, " bits ends at byte ", need, " (cut short?)"));
      }
    }
    SliceHeader h;
    h.width = s.width;
    h.height = s.height;
    h.dtype = NativeType(s);
    h.kind = Kind(s);
    gdcm::StringFilter sf;
    sf.SetFile(f);
    const gdcm::DataSet& ds = f.GetDataSet();
    Placement p;
    p.unit = "mm";
    if (auto ps = Numbers(sf, ds, kPixelSpacing, 2); ps && (*ps)[0] > 0 && (*ps)[1] > 0) {
      p.spacing.y = (*ps)[0];  // between rows
      p.spacing.x = (*ps)[1];  // between columns
    }
    h.placement = p;
    if (auto pos = Numbers(sf, ds, kImagePosition, 3))
      h.position = Vec3{(*pos)[0], (*pos)[1], (*pos)[2]};
    if (auto o = Numbers(sf, ds, kImageOrientation, 6)) {
      std::array<double, 6> a;
      std::copy(o->begin(), o->end(), a.begin());
      h.orientation = a;
    }
    if (ds.FindDataElement(kSeriesInstanceUid)) {
      h.series = std::string(absl::StripAsciiWhitespace(sf.ToString(kSeriesInstanceUid)));
      while (!h.series.empty() && h.series.back() == '\0') h.series.pop_back();
    }
    if (auto n = Numbers(sf, ds, kInstanceNumber, 1)) h.instance = static_cast<int64_t>((*n)[0]);
    SM_RETURN_IF_ERROR(
        CheckAllocation(int64_t{h.width} * h.height * 4 * 2, limits,
                        absl::StrCat(file, " (", h.width, "x", h.height, " ", h.kind, ")")));
    return h;
  }

  absl::Status ReadSlice(const std::string& file, const SliceHeader& expected, DType dtype,
                         std::span<std::byte> out) const override {
    SM_RETURN_IF_ERROR(CheckFileMeta(file));
    QuietGdcm();
    gdcm::ImageReader reader;
    reader.SetFileName(file.c_str());
    if (!reader.Read()) {
      return absl::InvalidArgumentError(absl::StrCat(
          file, ": DICOM image cannot be decoded (cut short, or a compression GDCM lacks)"));
    }
    SM_ASSIGN_OR_RETURN(StoredFormat s, ReadStoredFormat(file, reader.GetFile()));
    if (s.width != expected.width || s.height != expected.height) {
      return absl::InvalidArgumentError(absl::StrCat(file, ": slice is ", s.width, "x", s.height,
                                                     " but the first slice is ", expected.width,
                                                     "x", expected.height));
    }
    const gdcm::Image& image = reader.GetImage();
    const size_t n = static_cast<size_t>(s.width) * s.height;
    const unsigned long length = image.GetBufferLength();
    const gdcm::PixelFormat::ScalarType type = image.GetPixelFormat().GetScalarType();
    const size_t stored_bytes = image.GetPixelFormat().GetPixelSize();
    if (stored_bytes == 0 || length < n * stored_bytes) {
      return absl::InvalidArgumentError(
          absl::StrCat(file, ": DICOM pixel data holds ", length, " bytes for ", n, " pixels"));
    }
    // A file cut short inside uncompressed pixel data still "reads" (GDCM warns and keeps
    // what there is): its pixel element must hold every pixel.
    const gdcm::DataSet& ds = reader.GetFile().GetDataSet();
    if (ds.FindDataElement(kPixelData)) {
      const gdcm::ByteValue* bv = ds.GetDataElement(kPixelData).GetByteValue();
      if (bv != nullptr && static_cast<size_t>(bv->GetLength()) < n * stored_bytes) {
        return absl::InvalidArgumentError(
            absl::StrCat(file, ": DICOM PixelData (7FE0,0010) holds ",
                         static_cast<size_t>(bv->GetLength()), " bytes but ", s.width, "x",
                         s.height, " pixels need ", n * stored_bytes, " (cut short?)"));
      }
    }
    std::vector<char> buffer(length);
    if (!image.GetBuffer(buffer.data())) {
      return absl::InvalidArgumentError(
          absl::StrCat(file, ": DICOM pixel data cannot be decoded (corrupt or cut short?)"));
    }
    if (dtype == NativeType(s) && dtype != DType::kFloat32) {
      std::memcpy(out.data(), buffer.data(), out.size());
      return absl::OkStatus();
    }
    if (dtype != DType::kFloat32) {
      return absl::InvalidArgumentError(
          absl::StrCat(file, ": slice is ", Kind(s), " but the first slice is ", expected.kind));
    }
    float* f = reinterpret_cast<float*>(out.data());
    switch (type) {
      case gdcm::PixelFormat::UINT8:
        Rescale<uint8_t>(buffer.data(), n, s.slope, s.intercept, f);
        break;
      case gdcm::PixelFormat::INT8:
        Rescale<int8_t>(buffer.data(), n, s.slope, s.intercept, f);
        break;
      case gdcm::PixelFormat::UINT16:
        Rescale<uint16_t>(buffer.data(), n, s.slope, s.intercept, f);
        break;
      case gdcm::PixelFormat::INT16:
        Rescale<int16_t>(buffer.data(), n, s.slope, s.intercept, f);
        break;
      case gdcm::PixelFormat::UINT32:
        Rescale<uint32_t>(buffer.data(), n, s.slope, s.intercept, f);
        break;
      case gdcm::PixelFormat::INT32:
        Rescale<int32_t>(buffer.data(), n, s.slope, s.intercept, f);
        break;
      case gdcm::PixelFormat::FLOAT32:
        Rescale<float>(buffer.data(), n, s.slope, s.intercept, f);
        break;
      default:
        return absl::InvalidArgumentError(
            absl::StrCat(file, ": DICOM pixels of type ",
                         image.GetPixelFormat().GetScalarTypeAsString(), " are not read"));
    }
    return absl::OkStatus();
  }
};

}  // namespace

std::unique_ptr<SliceCodec> MakeDicomSliceCodec() { return std::make_unique<DicomSliceCodec>(); }

}  // namespace sheetmesh
