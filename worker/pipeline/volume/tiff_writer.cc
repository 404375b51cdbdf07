// The TIFF writers: one multi-page file, or a folder of one-page files (written beside
// the final name and renamed into place when finished).
#include <fcntl.h>
#include <sys/stat.h>
#include <tiffio.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/file_util.h"
#include "common/status_macros.h"
#include "worker/pipeline/volume/tiff_internal.h"
#include "worker/pipeline/volume/tiff_io.h"

namespace sheetmesh {
namespace {

using tiff_internal::InstallTiffHandlersOnce;
using tiff_internal::LastTiffError;
using tiff_internal::TiffPtr;

class TiffSink : public VolumeSink {
 public:
  TiffSink(TiffPtr tif, std::string part_path, VolumeInfo info, bool deflate)
      : tif_(std::move(tif)), part_path_(std::move(part_path)), deflate_(deflate) {
    info_ = std::move(info);
  }
  ~TiffSink() override {
    if (tif_ != nullptr) {
      tif_.reset();
      ::unlink(part_path_.c_str());
    }
  }

  absl::Status WriteSlices(int64_t count, std::span<const std::byte> data) override {
    SM_RETURN_IF_ERROR(Advance(count, data.size()));
    const size_t page =
        static_cast<size_t>(info_.dims.nx) * info_.dims.ny * BytesPerVoxel(info_.dtype);
    for (int64_t k = 0; k < count; ++k) {
      SM_RETURN_IF_ERROR(
          WritePage(tif_.get(), info_, data.subspan(k * page, page), deflate_, part_path_));
    }
    return absl::OkStatus();
  }

  absl::Status Finish() override {
    SM_RETURN_IF_ERROR(CheckComplete());
    tif_.reset();  // TIFFClose flushes the last directory
    const int fd = ::open(part_path_.c_str(), O_RDONLY);
    if (fd >= 0) {
      ::fsync(fd);
      ::close(fd);
    }
    if (std::rename(part_path_.c_str(), info_.path.c_str()) != 0) {
      return ErrnoStatus(errno, info_.path);
    }
    return absl::OkStatus();
  }

  static absl::Status WritePage(TIFF* tif, const VolumeInfo& info, std::span<const std::byte> data,
                                bool deflate, const std::string& where) {
    const uint32_t w = static_cast<uint32_t>(info.dims.nx);
    const uint32_t h = static_cast<uint32_t>(info.dims.ny);
    const int bpv = BytesPerVoxel(info.dtype);
    TIFFSetField(tif, TIFFTAG_IMAGEWIDTH, w);
    TIFFSetField(tif, TIFFTAG_IMAGELENGTH, h);
    TIFFSetField(tif, TIFFTAG_BITSPERSAMPLE, static_cast<uint16_t>(bpv * 8));
    TIFFSetField(tif, TIFFTAG_SAMPLESPERPIXEL, static_cast<uint16_t>(1));
    TIFFSetField(tif, TIFFTAG_SAMPLEFORMAT,
                 static_cast<uint16_t>(info.dtype == DType::kFloat32 ? SAMPLEFORMAT_IEEEFP
                                                                     : SAMPLEFORMAT_UINT));
    TIFFSetField(tif, TIFFTAG_PHOTOMETRIC, static_cast<uint16_t>(PHOTOMETRIC_MINISBLACK));
    TIFFSetField(tif, TIFFTAG_PLANARCONFIG, static_cast<uint16_t>(PLANARCONFIG_CONTIG));
    TIFFSetField(tif, TIFFTAG_COMPRESSION,
                 static_cast<uint16_t>(deflate ? COMPRESSION_ADOBE_DEFLATE : COMPRESSION_NONE));
    const uint32_t rows_per_strip = std::max<uint32_t>(1, (64u << 10) / (w * bpv));
    TIFFSetField(tif, TIFFTAG_ROWSPERSTRIP, std::min(rows_per_strip, h));
    const std::string desc =
        absl::StrCat("ImageJ=1.11a\nimages=", info.dims.nz, "\nslices=", info.dims.nz,
                     "\nunit=", info.placement.unit.empty() ? "pixel" : info.placement.unit,
                     "\nspacing=", info.placement.spacing.z, "\n");
    TIFFSetField(tif, TIFFTAG_IMAGEDESCRIPTION, desc.c_str());
    TIFFSetField(tif, TIFFTAG_RESOLUTIONUNIT, static_cast<uint16_t>(RESUNIT_NONE));
    TIFFSetField(tif, TIFFTAG_XRESOLUTION, static_cast<float>(1.0 / info.placement.spacing.x));
    TIFFSetField(tif, TIFFTAG_YRESOLUTION, static_cast<float>(1.0 / info.placement.spacing.y));
    const size_t row_bytes = static_cast<size_t>(w) * bpv;
    std::vector<std::byte> row(row_bytes);
    for (uint32_t r = 0; r < h; ++r) {
      // libtiff may encode in place, so hand it a copy.
      std::memcpy(row.data(), data.data() + r * row_bytes, row_bytes);
      if (TIFFWriteScanline(tif, row.data(), r, 0) < 0) {
        return absl::InternalError(absl::StrCat(where, ": writing row ", r, ": ", LastTiffError()));
      }
    }
    if (!TIFFWriteDirectory(tif)) {
      return absl::InternalError(absl::StrCat(where, ": writing page: ", LastTiffError()));
    }
    return absl::OkStatus();
  }

 private:
  TiffPtr tif_;
  std::string part_path_;
  bool deflate_;
};

class TiffFolderSink : public VolumeSink {
 public:
  explicit TiffFolderSink(VolumeInfo info) { info_ = std::move(info); }

  absl::Status WriteSlices(int64_t count, std::span<const std::byte> data) override {
    const int64_t first = slices_written_;
    SM_RETURN_IF_ERROR(Advance(count, data.size()));
    const size_t page =
        static_cast<size_t>(info_.dims.nx) * info_.dims.ny * BytesPerVoxel(info_.dtype);
    for (int64_t k = 0; k < count; ++k) {
      char name[32];
      std::snprintf(name, sizeof(name), "slice_%05lld.tif", static_cast<long long>(first + k));
      const std::string path = (std::filesystem::path(info_.path) / name).string();
      const std::string part = path + ".part";
      TiffPtr tif(TIFFOpen(part.c_str(), "w"));
      if (tif == nullptr) {
        return absl::InternalError(absl::StrCat(part, ": cannot create: ", LastTiffError()));
      }
      VolumeInfo one = info_;
      one.dims.nz = 1;
      absl::Status st =
          TiffSink::WritePage(tif.get(), one, data.subspan(k * page, page), false, part);
      tif.reset();
      if (!st.ok() || std::rename(part.c_str(), path.c_str()) != 0) {
        ::unlink(part.c_str());
        return st.ok() ? ErrnoStatus(errno, path) : st;
      }
    }
    return absl::OkStatus();
  }

  absl::Status Finish() override { return CheckComplete(); }
};

}  // namespace

absl::StatusOr<std::unique_ptr<VolumeSink>> CreateTiffWriter(const std::string& path,
                                                             const VolumeInfo& info, bool deflate) {
  InstallTiffHandlersOnce();
  const std::string part = path + ".part";
  const int64_t bytes = info.dims.num_voxels() * BytesPerVoxel(info.dtype);
  TiffPtr tif(TIFFOpen(part.c_str(), bytes > (int64_t{1} << 31) ? "w8" : "w"));
  if (tif == nullptr) {
    return absl::InvalidArgumentError(absl::StrCat(part, ": cannot create: ", LastTiffError()));
  }
  VolumeInfo out = info;
  out.path = path;
  out.format = "tiff";
  return std::make_unique<TiffSink>(std::move(tif), part, std::move(out), deflate);
}

absl::StatusOr<std::unique_ptr<VolumeSink>> CreateTiffFolderWriter(const std::string& folder,
                                                                   const VolumeInfo& info) {
  InstallTiffHandlersOnce();
  SM_RETURN_IF_ERROR(MakeDirs(folder));
  VolumeInfo out = info;
  out.path = folder;
  out.format = "tiff-folder";
  return std::make_unique<TiffFolderSink>(std::move(out));
}

}  // namespace sheetmesh
