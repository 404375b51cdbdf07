#include "worker/pipeline/volume/slice_stack.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/file_util.h"
#include "common/status_macros.h"

namespace sheetmesh {
namespace {

class StackSource : public VolumeSource {
 public:
  StackSource(std::vector<std::string> files, std::shared_ptr<const SliceCodec> codec,
              SliceHeader first, VolumeInfo info)
      : files_(std::move(files)), codec_(std::move(codec)), first_(std::move(first)) {
    info_ = std::move(info);
  }

  absl::Status ReadSlices(int64_t z0, int64_t count, std::span<std::byte> out) override {
    SM_RETURN_IF_ERROR(CheckSliceRequest(z0, count, out.size()));
    const size_t slice =
        static_cast<size_t>(info_.dims.nx) * info_.dims.ny * BytesPerVoxel(info_.dtype);
    for (int64_t k = 0; k < count; ++k) {
      SM_RETURN_IF_ERROR(
          codec_->ReadSlice(files_[z0 + k], first_, info_.dtype, out.subspan(k * slice, slice)));
    }
    return absl::OkStatus();
  }

 private:
  std::vector<std::string> files_;
  std::shared_ptr<const SliceCodec> codec_;
  SliceHeader first_;
};

std::vector<std::shared_ptr<const SliceCodec>> AllCodecs() {
  return {MakeTiffSliceCodec(), MakePngSliceCodec(), MakeJpegSliceCodec(), MakeDicomSliceCodec()};
}

std::string Describe(const SliceHeader& h) {
  return absl::StrCat(h.width, "x", h.height, " ", h.kind);
}

// The normal of a DICOM slice: the cross product of its row and column directions.
Vec3 Normal(const std::array<double, 6>& o) {
  return {o[1] * o[5] - o[2] * o[4], o[2] * o[3] - o[0] * o[5], o[0] * o[4] - o[1] * o[3]};
}

struct Slice {
  std::string file;
  SliceHeader header;
};

// Orders DICOM slices along their normal and sets the z spacing and origin from the
// positions: slices of one series, evenly spaced, none twice.
absl::Status PlaceDicomSlices(const std::string& folder, std::vector<Slice>& slices,
                              Placement* placement) {
  std::map<std::string, int> series;
  for (const Slice& s : slices) ++series[s.header.series];
  if (series.size() > 1) {
    std::string list;
    for (const auto& [uid, n] : series) {
      absl::StrAppend(&list, list.empty() ? "" : "; ", uid.empty() ? "(none)" : uid, ": ", n,
                      " files");
    }
    return absl::InvalidArgumentError(absl::StrCat(folder, ": the folder holds ", series.size(),
                                                   " DICOM series (SeriesInstanceUID ", list,
                                                   "); put one series in a folder"));
  }
  const bool positioned = std::all_of(slices.begin(), slices.end(), [](const Slice& s) {
    return s.header.position.has_value() && s.header.orientation.has_value();
  });
  if (!positioned) {
    const bool numbered = std::all_of(slices.begin(), slices.end(),
                                      [](const Slice& s) { return s.header.instance.has_value(); });
    if (numbered) {
      std::stable_sort(slices.begin(), slices.end(), [](const Slice& a, const Slice& b) {
        return *a.header.instance < *b.header.instance;
      });
    }
    return absl::OkStatus();  // no positions: the z spacing stays what the user gives
  }
  const Vec3 n = Normal(*slices[0].header.orientation);
  auto along = [&](const Slice& s) {
    const Vec3& p = *s.header.position;
    return p.x * n.x + p.y * n.y + p.z * n.z;
  };
  std::stable_sort(slices.begin(), slices.end(),
                   [&](const Slice& a, const Slice& b) { return along(a) < along(b); });
  placement->origin = *slices[0].header.position;
  if (slices.size() < 2) return absl::OkStatus();
  std::vector<double> gaps;
  for (size_t i = 1; i < slices.size(); ++i)
    gaps.push_back(along(slices[i]) - along(slices[i - 1]));
  std::vector<double> sorted = gaps;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double step = sorted[sorted.size() / 2];
  for (size_t i = 0; i < gaps.size(); ++i) {
    if (gaps[i] < 1e-6) {
      return absl::InvalidArgumentError(absl::StrCat(
          slices[i].file, " and ", slices[i + 1].file,
          " lie at the same position (ImagePositionPatient): two acquisitions in one folder?"));
    }
    if (std::abs(gaps[i] - step) > 0.01 * step + 1e-4) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s to %s: slices %.4g mm apart where the others are %.4g mm (ImagePositionPatient): "
          "a slice is missing or the spacing is uneven",
          slices[i].file, slices[i + 1].file, gaps[i], step));
    }
  }
  placement->spacing.z = step;
  return absl::OkStatus();
}

// Files numbered alike (a prefix, a number, a suffix) must follow each other at one step: a
// number that is missing is a slice that is missing, and the volume would silently close
// the gap. kInvalidArgument naming the folder, the missing number and its neighbours.
absl::Status CheckNumbering(const std::string& path, const std::vector<std::string>& files) {
  if (files.size() < 3) return absl::OkStatus();
  struct Numbered {
    std::string prefix, suffix;
    int64_t number = 0;
  };
  std::vector<Numbered> n;
  for (const std::string& f : files) {
    const std::string name = std::filesystem::path(f).filename().string();
    size_t end = name.size();
    while (end > 0 && !absl::ascii_isdigit(name[end - 1])) --end;
    size_t begin = end;
    while (begin > 0 && absl::ascii_isdigit(name[begin - 1])) --begin;
    Numbered x;
    if (begin == end || end - begin > 15) return absl::OkStatus();  // not numbered
    x.prefix = name.substr(0, begin);
    x.suffix = name.substr(end);
    x.number = std::stoll(name.substr(begin, end - begin));
    if (!n.empty() && (x.prefix != n[0].prefix || x.suffix != n[0].suffix)) {
      return absl::OkStatus();  // named otherwise: the order is all there is
    }
    n.push_back(std::move(x));
  }
  int64_t step = INT64_MAX;
  for (size_t i = 1; i < n.size(); ++i) step = std::min(step, n[i].number - n[i - 1].number);
  for (size_t i = 1; i < n.size(); ++i) {
    const int64_t gap = n[i].number - n[i - 1].number;
    if (gap == step && step > 0) continue;
    const std::string a = std::filesystem::path(files[i - 1]).filename().string();
    const std::string b = std::filesystem::path(files[i]).filename().string();
    if (step <= 0) {
      return absl::InvalidArgumentError(absl::StrCat(
          path, ": ", a, " and ", b, " have the same slice number ", n[i].number, ": keep one"));
    }
    return absl::InvalidArgumentError(absl::StrCat(
        path, ": slice number ", n[i - 1].number + step, " is missing (between ", a, " and ", b,
        "; the other ", n.size(), " files go by ", step,
        "): a volume without it would close the gap; restore the slice, or stack the files "
        "apart"));
  }
  return absl::OkStatus();
}

absl::StatusOr<std::unique_ptr<VolumeSource>> OpenStack(const std::string& path,
                                                        std::vector<std::string> files,
                                                        std::shared_ptr<const SliceCodec> codec,
                                                        const VolumeLimits& limits,
                                                        const std::string& format) {
  if (static_cast<int64_t>(files.size()) > limits.max_extent) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": ", files.size(), " slices, more than ", limits.max_extent));
  }
  std::sort(files.begin(), files.end(), NaturalLess);
  // DICOM slices say where they lie (checked below); other files only by their names.
  if (codec->name() != "dicom") SM_RETURN_IF_ERROR(CheckNumbering(path, files));
  // Every slice's header up front, so that a mismatch fails before any work.
  std::vector<Slice> slices;
  slices.reserve(files.size());
  for (const std::string& f : files) {
    SM_ASSIGN_OR_RETURN(SliceHeader h, codec->ReadHeader(f, limits));
    if (!slices.empty()) {
      const Slice& s0 = slices[0];
      if (h.width != s0.header.width || h.height != s0.header.height ||
          (h.dtype != s0.header.dtype && codec->name() != "dicom")) {
        return absl::InvalidArgumentError(
            absl::StrCat(f, " is ", Describe(h), " but ", s0.file, " is ", Describe(s0.header)));
      }
    }
    slices.push_back({f, std::move(h)});
  }
  VolumeInfo info;
  info.path = path;
  info.format = format;
  info.dtype = slices[0].header.dtype;
  if (slices[0].header.placement) info.placement = *slices[0].header.placement;
  if (codec->name() == "dicom") {
    SM_RETURN_IF_ERROR(PlaceDicomSlices(path, slices, &info.placement));
    // Slices that rescale, or differ in type, read as float32.
    for (const Slice& s : slices) {
      if (s.header.dtype != info.dtype) info.dtype = DType::kFloat32;
    }
  }
  info.dims = {slices[0].header.width, slices[0].header.height,
               static_cast<int64_t>(slices.size())};
  SM_RETURN_IF_ERROR(CheckDims(info.dims, info.dtype, limits, path));
  if (info.dtype != slices[0].header.dtype ||
      (info.dtype == DType::kFloat32 && codec->name() == "dicom" &&
       slices[0].header.kind.rfind("float", 0) != 0)) {
    absl::StrAppend(&info.format, " ", slices[0].header.kind, "→float32");
  }
  files.clear();
  for (Slice& s : slices) files.push_back(std::move(s.file));
  SliceHeader first = std::move(slices[0].header);
  return std::make_unique<StackSource>(std::move(files), std::move(codec), std::move(first),
                                       std::move(info));
}

bool Ignored(const std::filesystem::path& p) {
  const std::string name = p.filename().string();
  return name.empty() || name[0] == '.' || absl::AsciiStrToUpper(name) == "DICOMDIR";
}

}  // namespace

bool NaturalLess(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (absl::ascii_isdigit(a[i]) && absl::ascii_isdigit(b[j])) {
      size_t ie = i, je = j;
      while (ie < a.size() && absl::ascii_isdigit(a[ie])) ++ie;
      while (je < b.size() && absl::ascii_isdigit(b[je])) ++je;
      absl::string_view da(a.data() + i, ie - i), db(b.data() + j, je - j);
      while (da.size() > 1 && da[0] == '0') da.remove_prefix(1);
      while (db.size() > 1 && db[0] == '0') db.remove_prefix(1);
      if (da.size() != db.size()) return da.size() < db.size();
      if (da != db) return da < db;
      i = ie;
      j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

absl::StatusOr<std::unique_ptr<VolumeSource>> OpenSliceFolderOf(const std::string& folder,
                                                                const std::string& codec_name,
                                                                const VolumeLimits& limits) {
  std::vector<std::shared_ptr<const SliceCodec>> codecs = AllCodecs();
  std::map<std::string, std::vector<std::string>> by_codec;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec)) {
    if (!entry.is_regular_file() || Ignored(entry.path())) continue;
    const std::string file = entry.path().string();
    for (const auto& c : codecs) {
      if (c->Claims(file)) {
        by_codec[c->name()].push_back(file);
        break;
      }
    }
  }
  if (ec) return ErrnoStatus(ec.value(), folder);
  if (!codec_name.empty()) {
    auto it = by_codec.find(codec_name);
    if (it == by_codec.end()) {
      return absl::NotFoundError(
          absl::StrCat(folder, ": the folder holds no ", codec_name, " slices"));
    }
    by_codec = {*it};
  }
  if (by_codec.empty()) {
    return absl::NotFoundError(absl::StrCat(
        folder, ": the folder holds no slices (.tif/.tiff, .png, .jpg/.jpeg or DICOM files)"));
  }
  if (by_codec.size() > 1) {
    std::string list;
    for (const auto& [name, files] : by_codec) {
      absl::StrAppend(&list, list.empty() ? "" : ", ", files.size(), " ", name);
    }
    return absl::InvalidArgumentError(
        absl::StrCat(folder, ": the folder mixes slice formats (", list,
                     "); keep one format per folder or give it (input.format)"));
  }
  const std::string name = by_codec.begin()->first;
  std::shared_ptr<const SliceCodec> codec;
  for (const auto& c : codecs) {
    if (c->name() == name) codec = c;
  }
  return OpenStack(folder, std::move(by_codec.begin()->second), std::move(codec), limits,
                   name == "dicom" ? "dicom-series" : name + "-folder");
}

absl::StatusOr<std::unique_ptr<VolumeSource>> OpenSliceFolder(const std::string& folder,
                                                              const VolumeLimits& limits) {
  return OpenSliceFolderOf(folder, "", limits);
}

absl::StatusOr<std::unique_ptr<VolumeSource>> OpenSingleSlice(const std::string& file,
                                                              const std::string& codec_name,
                                                              const VolumeLimits& limits) {
  for (auto& c : AllCodecs()) {
    if (c->name() == codec_name) return OpenStack(file, {file}, std::move(c), limits, codec_name);
  }
  return absl::InvalidArgumentError(absl::StrCat(file, ": no slice format '", codec_name, "'"));
}

}  // namespace sheetmesh
