#include "worker/pipeline/volume/tiff_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <tiffio.h>
#include <unistd.h>

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "common/file_util.h"
#include "common/status_macros.h"
#include "worker/pipeline/volume/slice_stack.h"
#include "worker/pipeline/volume/tiff_internal.h"

namespace sheetmesh {
namespace {

using tiff_internal::LastTiffError;
using tiff_internal::TiffPtr;

// The layout of one page.
struct PageFormat {
  uint32_t width = 0;
  uint32_t height = 0;
  DType dtype = DType::kUInt8;
  bool tiled = false;
  bool min_is_white = false;  // integer samples are read as (max - stored)
  friend bool operator==(const PageFormat&, const PageFormat&) = default;
};

absl::StatusOr<PageFormat> ReadPageFormat(TIFF* tif, const std::string& where) {
  PageFormat f;
  uint16_t bits = 0, spp = 1, format = SAMPLEFORMAT_UINT, planar = PLANARCONFIG_CONTIG;
  if (!TIFFGetField(tif, TIFFTAG_IMAGEWIDTH, &f.width) ||
      !TIFFGetField(tif, TIFFTAG_IMAGELENGTH, &f.height)) {
    return absl::InvalidArgumentError(absl::StrCat(where, ": missing image width or length"));
  }
  TIFFGetFieldDefaulted(tif, TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLESPERPIXEL, &spp);
  TIFFGetFieldDefaulted(tif, TIFFTAG_SAMPLEFORMAT, &format);
  TIFFGetFieldDefaulted(tif, TIFFTAG_PLANARCONFIG, &planar);
  if (f.width == 0 || f.height == 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(where, ": page size ", f.width, "x", f.height, " is empty"));
  }
  if (spp != 1) {
    return absl::InvalidArgumentError(absl::StrCat(
        where, ": ", spp, " samples per pixel; only single-channel (grey) images are supported"));
  }
  if (bits == 8 && format == SAMPLEFORMAT_UINT) {
    f.dtype = DType::kUInt8;
  } else if (bits == 16 && format == SAMPLEFORMAT_UINT) {
    f.dtype = DType::kUInt16;
  } else if (bits == 32 && format == SAMPLEFORMAT_IEEEFP) {
    f.dtype = DType::kFloat32;
  } else {
    const char* kind = format == SAMPLEFORMAT_INT      ? "signed integer"
                       : format == SAMPLEFORMAT_IEEEFP ? "float"
                                                       : "unsigned integer";
    return absl::InvalidArgumentError(
        absl::StrCat(where, ": ", bits, "-bit ", kind,
                     " samples are not supported; use 8- or 16-bit unsigned or 32-bit float"));
  }
  f.tiled = TIFFIsTiled(tif) != 0;
  uint16_t photometric = PHOTOMETRIC_MINISBLACK;
  TIFFGetFieldDefaulted(tif, TIFFTAG_PHOTOMETRIC, &photometric);
  f.min_is_white = photometric == PHOTOMETRIC_MINISWHITE && f.dtype != DType::kFloat32;
  return f;
}

absl::Status ReadPageStored(TIFF* tif, const PageFormat& f, std::span<std::byte> out,
                            const std::string& where);

// Reads the current page into `out` (width*height voxels of f.dtype). A min-is-white page
// stores 0 for white: as the TIFF specification says, its intensity is max - stored.
absl::Status ReadPage(TIFF* tif, const PageFormat& f, std::span<std::byte> out,
                      const std::string& where) {
  SM_RETURN_IF_ERROR(ReadPageStored(tif, f, out, where));
  if (!f.min_is_white) return absl::OkStatus();
  if (f.dtype == DType::kUInt8) {
    for (std::byte& b : out) b = ~b;
  } else {
    uint16_t* v = reinterpret_cast<uint16_t*>(out.data());
    for (size_t i = 0; i < out.size() / 2; ++i) v[i] = static_cast<uint16_t>(~v[i]);
  }
  return absl::OkStatus();
}

absl::Status ReadPageStored(TIFF* tif, const PageFormat& f, std::span<std::byte> out,
                            const std::string& where) {
  const int bpv = BytesPerVoxel(f.dtype);
  const size_t row_bytes = static_cast<size_t>(f.width) * bpv;
  if (!f.tiled) {
    if (static_cast<size_t>(TIFFScanlineSize64(tif)) != row_bytes) {
      return absl::InvalidArgumentError(absl::StrCat(
          where, ": scanline of ", TIFFScanlineSize64(tif), " bytes, expected ", row_bytes));
    }
    for (uint32_t row = 0; row < f.height; ++row) {
      if (TIFFReadScanline(tif, out.data() + row * row_bytes, row, 0) < 0) {
        return absl::InvalidArgumentError(
            absl::StrCat(where, ": row ", row, " is unreadable: ", LastTiffError()));
      }
    }
    return absl::OkStatus();
  }
  uint32_t tw = 0, th = 0;
  TIFFGetField(tif, TIFFTAG_TILEWIDTH, &tw);
  TIFFGetField(tif, TIFFTAG_TILELENGTH, &th);
  if (tw == 0 || th == 0) {
    return absl::InvalidArgumentError(absl::StrCat(where, ": tile size ", tw, "x", th));
  }
  // Checked against the page at open: a tile holds at most what the page does plus padding.
  const uint64_t tile_bytes = TIFFTileSize64(tif);
  const uint64_t page = uint64_t{f.width} * f.height * bpv;
  if (tile_bytes == 0 || tile_bytes > uint64_t{4} * tw * th * bpv + 4096 ||
      tile_bytes > 4 * page + (uint64_t{1} << 20)) {
    return absl::InvalidArgumentError(
        absl::StrCat(where, ": tile of ", tw, "x", th, " takes ", tile_bytes, " bytes"));
  }
  std::vector<std::byte> tile(static_cast<size_t>(tile_bytes));
  if (tile.size() < static_cast<size_t>(tw) * th * bpv) {
    return absl::InvalidArgumentError(absl::StrCat(where, ": tile buffer too small"));
  }
  for (uint32_t ty = 0; ty < f.height; ty += th) {
    for (uint32_t tx = 0; tx < f.width; tx += tw) {
      if (TIFFReadTile(tif, tile.data(), tx, ty, 0, 0) < 0) {
        return absl::InvalidArgumentError(
            absl::StrCat(where, ": tile at (", tx, ",", ty, ") is unreadable: ", LastTiffError()));
      }
      const uint32_t w = std::min(tw, f.width - tx);
      const uint32_t h = std::min(th, f.height - ty);
      for (uint32_t r = 0; r < h; ++r) {
        std::memcpy(out.data() + ((ty + r) * static_cast<size_t>(f.width) + tx) * bpv,
                    tile.data() + static_cast<size_t>(r) * tw * bpv, static_cast<size_t>(w) * bpv);
      }
    }
  }
  return absl::OkStatus();
}

// ImageJ writes "unit=micron\nspacing=2.5\n" into the description; XResolution holds
// pixels per unit.
void ReadPlacement(TIFF* tif, Placement* p) {
  char* desc = nullptr;
  if (!TIFFGetField(tif, TIFFTAG_IMAGEDESCRIPTION, &desc) || desc == nullptr) return;
  if (std::strncmp(desc, "ImageJ=", 7) != 0) return;
  for (absl::string_view line : absl::StrSplit(desc, '\n')) {
    std::pair<absl::string_view, absl::string_view> kv = absl::StrSplit(line, '=');
    double v = 0;
    if (kv.first == "unit") {
      p->unit = std::string(kv.second);
    } else if (kv.first == "spacing" && absl::SimpleAtod(kv.second, &v) && v > 0) {
      p->spacing.z = v;
    }
  }
  float xr = 0, yr = 0;
  if (TIFFGetField(tif, TIFFTAG_XRESOLUTION, &xr) && xr > 0) p->spacing.x = 1.0 / xr;
  if (TIFFGetField(tif, TIFFTAG_YRESOLUTION, &yr) && yr > 0) p->spacing.y = 1.0 / yr;
}

absl::StatusOr<int64_t> FileSize(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) return ErrnoStatus(errno, path);
  return static_cast<int64_t>(st.st_size);
}

absl::StatusOr<TiffPtr> OpenTiff(const std::string& path) {
  tiff_internal::InstallTiffHandlersOnce();
  if (::access(path.c_str(), R_OK) != 0) return ErrnoStatus(errno, path);
  // "m": no memory mapping; a file that shrinks while it is read is then a read error,
  // not SIGBUS.
  TiffPtr tif(TIFFOpen(path.c_str(), "rm"));
  if (tif == nullptr) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": not a readable TIFF: ", LastTiffError()));
  }
  return tif;
}

std::string FormatName(const PageFormat& f) {
  return absl::StrCat(f.width, "x", f.height, " ", DTypeName(f.dtype));
}

// The most a TIFF compression scheme inflates its data (a bound, for refusing pages that
// claim more voxels than their bytes can hold). Deflate's format tops at 1032:1, LZW near
// 1300:1 and PackBits 128:1; for the rest the memory budget alone guards.
double MaxExpansion(uint16_t compression) {
  switch (compression) {
    case COMPRESSION_NONE:
      return 1;
    case COMPRESSION_PACKBITS:
      return 130;
    case COMPRESSION_LZW:
      return 1400;
    case COMPRESSION_DEFLATE:
    case COMPRESSION_ADOBE_DEFLATE:
      return 1100;
    default:
      return 1e9;
  }
}

// Before any voxel of the current page is read: the page must fit the memory budget, and
// its strips (or tiles) must lie within the file and hold enough bytes for its voxels.
absl::Status CheckPageData(TIFF* tif, const PageFormat& f, int64_t file_size,
                           const VolumeLimits& limits, const std::string& where) {
  const int64_t page_bytes = int64_t{f.width} * f.height * BytesPerVoxel(f.dtype);
  SM_RETURN_IF_ERROR(
      CheckAllocation(page_bytes, limits, absl::StrCat(where, " (", FormatName(f), ")")));
  const bool tiled = TIFFIsTiled(tif) != 0;
  const uint32_t n = tiled ? TIFFNumberOfTiles(tif) : TIFFNumberOfStrips(tif);
  uint64_t* offsets = nullptr;
  uint64_t* counts = nullptr;
  if (!TIFFGetField(tif, tiled ? TIFFTAG_TILEOFFSETS : TIFFTAG_STRIPOFFSETS, &offsets) ||
      !TIFFGetField(tif, tiled ? TIFFTAG_TILEBYTECOUNTS : TIFFTAG_STRIPBYTECOUNTS, &counts) ||
      offsets == nullptr || counts == nullptr || n == 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(where, ": has no ", tiled ? "tile" : "strip", " offsets or byte counts"));
  }
  uint64_t held = 0;
  for (uint32_t i = 0; i < n; ++i) {
    if (offsets[i] > static_cast<uint64_t>(file_size) ||
        counts[i] > static_cast<uint64_t>(file_size) - offsets[i]) {
      return absl::InvalidArgumentError(absl::StrCat(
          where, ": ", tiled ? "tile " : "strip ", i, " lies at bytes ", offsets[i], " to ",
          offsets[i] + counts[i], " but the file has ", file_size, " (cut short?)"));
    }
    held += counts[i];
  }
  uint16_t compression = COMPRESSION_NONE;
  TIFFGetFieldDefaulted(tif, TIFFTAG_COMPRESSION, &compression);
  if (static_cast<double>(page_bytes) > static_cast<double>(held) * MaxExpansion(compression)) {
    return absl::InvalidArgumentError(absl::StrCat(
        where, ": ", FormatName(f), " needs ", page_bytes, " bytes but its ", n,
        tiled ? " tiles" : " strips", " hold ", held,
        compression == COMPRESSION_NONE ? " (cut short?)"
                                        : ", more than its compression can give (corrupt?)"));
  }
  return absl::OkStatus();
}

class MultiPageSource : public VolumeSource {
 public:
  MultiPageSource(TiffPtr tif, PageFormat format, VolumeInfo info)
      : tif_(std::move(tif)), format_(format) {
    info_ = std::move(info);
  }

  absl::Status ReadSlices(int64_t z0, int64_t count, std::span<std::byte> out) override {
    const size_t page_bytes =
        static_cast<size_t>(format_.width) * format_.height * BytesPerVoxel(format_.dtype);
    SM_RETURN_IF_ERROR(CheckSliceRequest(z0, count, out.size()));
    for (int64_t k = 0; k < count; ++k) {
      const int64_t z = z0 + k;
      const std::string where = absl::StrCat(info_.path, " page ", z);
      // Moving to the next directory is cheap; jumping re-walks the chain of pages.
      const bool ok = (z == current_ + 1) ? TIFFReadDirectory(tif_.get())
                                          : TIFFSetDirectory(tif_.get(), static_cast<tdir_t>(z));
      if (!ok) {
        return absl::InvalidArgumentError(
            absl::StrCat(where, ": cannot open page: ", LastTiffError()));
      }
      current_ = z;
      // Pages agree in size and type (checked at open) but may differ in strips vs tiles.
      SM_ASSIGN_OR_RETURN(PageFormat f, ReadPageFormat(tif_.get(), where));
      SM_RETURN_IF_ERROR(ReadPage(tif_.get(), f, out.subspan(k * page_bytes, page_bytes), where));
    }
    return absl::OkStatus();
  }

 private:
  TiffPtr tif_;
  PageFormat format_;
  int64_t current_ = 0;  // the directory libtiff is on
};

// One single-page TIFF as a slice of a folder.
class TiffSliceCodec : public SliceCodec {
 public:
  std::string name() const override { return "tiff"; }
  bool Claims(const std::string& file) const override {
    const std::string ext = absl::AsciiStrToLower(std::filesystem::path(file).extension().string());
    return ext == ".tif" || ext == ".tiff";
  }
  absl::StatusOr<SliceHeader> ReadHeader(const std::string& file,
                                         const VolumeLimits& limits) const override {
    SM_ASSIGN_OR_RETURN(TiffPtr tif, OpenTiff(file));
    SM_ASSIGN_OR_RETURN(PageFormat f, ReadPageFormat(tif.get(), file));
    SM_ASSIGN_OR_RETURN(const int64_t size, FileSize(file));
    SM_RETURN_IF_ERROR(CheckPageData(tif.get(), f, size, limits, file));
    SliceHeader h;
    h.width = f.width;
    h.height = f.height;
    h.dtype = f.dtype;
    h.kind = std::string(DTypeName(f.dtype));
    Placement p;
    ReadPlacement(tif.get(), &p);
    h.placement = p;
    return h;
  }
  absl::Status ReadSlice(const std::string& file, const SliceHeader& expected, DType dtype,
                         std::span<std::byte> out) const override {
    SM_ASSIGN_OR_RETURN(TiffPtr tif, OpenTiff(file));
    SM_ASSIGN_OR_RETURN(PageFormat f, ReadPageFormat(tif.get(), file));
    if (f.width != expected.width || f.height != expected.height || f.dtype != dtype) {
      return absl::InvalidArgumentError(absl::StrCat(file, ": slice is ", FormatName(f),
                                                     " but the first slice is ", expected.width,
                                                     "x", expected.height, " ", DTypeName(dtype)));
    }
    return ReadPage(tif.get(), f, out, file);
  }
};

}  // namespace

absl::StatusOr<std::unique_ptr<VolumeSource>> OpenTiffVolume(const std::string& path,
                                                             const VolumeLimits& limits) {
  SM_ASSIGN_OR_RETURN(TiffPtr tif, OpenTiff(path));
  SM_ASSIGN_OR_RETURN(PageFormat first, ReadPageFormat(tif.get(), absl::StrCat(path, " page 0")));
  VolumeInfo info;
  info.path = path;
  info.format = "tiff";
  info.dtype = first.dtype;
  ReadPlacement(tif.get(), &info.placement);
  SM_ASSIGN_OR_RETURN(const int64_t file_size, FileSize(path));
  SM_RETURN_IF_ERROR(
      CheckPageData(tif.get(), first, file_size, limits, absl::StrCat(path, " page 0")));
  // Every page must agree with the first, and its data lie in the file, before any voxel is
  // read.
  int64_t pages = 1;
  while (!TIFFLastDirectory(tif.get())) {
    const std::string where = absl::StrCat(path, " page ", pages);
    if (!TIFFReadDirectory(tif.get())) {
      return absl::InvalidArgumentError(absl::StrCat(where, " cannot be read (", LastTiffError(),
                                                     "): the file is cut short or corrupt"));
    }
    SM_ASSIGN_OR_RETURN(PageFormat f, ReadPageFormat(tif.get(), where));
    if (!(f.width == first.width && f.height == first.height && f.dtype == first.dtype)) {
      return absl::InvalidArgumentError(
          absl::StrCat(where, " is ", FormatName(f), " but page 0 is ", FormatName(first)));
    }
    SM_RETURN_IF_ERROR(CheckPageData(tif.get(), f, file_size, limits, where));
    ++pages;
    if (pages > limits.max_extent) {
      return absl::InvalidArgumentError(
          absl::StrCat(path, ": more than ", limits.max_extent, " pages"));
    }
  }
  info.dims = {first.width, first.height, pages};
  SM_RETURN_IF_ERROR(CheckDims(info.dims, info.dtype, limits, path));
  if (!TIFFSetDirectory(tif.get(), 0)) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": cannot rewind: ", LastTiffError()));
  }
  return std::make_unique<MultiPageSource>(std::move(tif), first, std::move(info));
}

std::unique_ptr<SliceCodec> MakeTiffSliceCodec() { return std::make_unique<TiffSliceCodec>(); }

absl::StatusOr<std::unique_ptr<VolumeSource>> OpenTiffFolder(const std::string& folder,
                                                             const VolumeLimits& limits) {
  return OpenSliceFolderOf(folder, "tiff", limits);
}

}  // namespace sheetmesh
