#include "worker/pipeline/volume/volume_open.h"

#include <cstring>
#include <filesystem>
#include <regex>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "worker/pipeline/volume/array_io.h"
#include "worker/pipeline/volume/hdf5_io.h"
#include "worker/pipeline/volume/nrrd_io.h"
#include "worker/pipeline/volume/slice_stack.h"
#include "worker/pipeline/volume/tiff_io.h"
#include "worker/pipeline/volume/vdb_io.h"

namespace sheetmesh {
namespace {

// Applies the user's placement on top of what the file said.
class PlacedSource : public VolumeSource {
 public:
  PlacedSource(std::unique_ptr<VolumeSource> inner, const OpenOptions& o)
      : inner_(std::move(inner)) {
    info_ = inner_->info();
    if (o.spacing) info_.placement.spacing = *o.spacing;
    if (o.origin) info_.placement.origin = *o.origin;
    if (!o.unit.empty()) info_.placement.unit = o.unit;
  }
  absl::Status ReadSlices(int64_t z0, int64_t count, std::span<std::byte> out) override {
    return inner_->ReadSlices(z0, count, out);
  }
  bool CanMap() const override { return inner_->CanMap(); }
  absl::StatusOr<MappedSlices> MapSlices(int64_t z0, int64_t count) override {
    return inner_->MapSlices(z0, count);
  }
  std::optional<std::vector<FileRange>> BytesRead(int64_t z0, int64_t count) const override {
    return inner_->BytesRead(z0, count);
  }

 private:
  std::unique_ptr<VolumeSource> inner_;
};

// A box of the inner source: its slices read one at a time (a mapped slice where the reader
// maps) and cut to the region's rows, so that a brick of a large volume costs its own slices'
// rows, not the volume's slabs.
class RegionSource : public VolumeSource {
 public:
  RegionSource(std::unique_ptr<VolumeSource> inner, const VoxelRegion& region)
      : inner_(std::move(inner)), region_(region) {
    info_ = inner_->info();
    info_.dims = region.dims();
    info_.placement.origin =
        info_.placement.ToPhysical(Vec3(region.lo.x, region.lo.y, region.lo.z));
  }
  absl::Status ReadSlices(int64_t z0, int64_t count, std::span<std::byte> out) override {
    SM_RETURN_IF_ERROR(CheckSliceRequest(z0, count, out.size()));
    const Dims& full = inner_->info().dims;
    const int64_t bpv = BytesPerVoxel(info_.dtype);
    const int64_t row = info_.dims.nx * bpv;
    const int64_t slice = full.nx * full.ny * bpv;
    const int64_t out_slice = info_.dims.ny * row;
    for (int64_t k = 0; k < count; ++k) {
      const int64_t z = region_.lo.z + z0 + k;
      std::span<const std::byte> data;
      MappedSlices mapped;
      if (inner_->CanMap()) {
        SM_ASSIGN_OR_RETURN(mapped, inner_->MapSlices(z, 1));
        data = mapped.data();
      } else {
        buffer_.resize(static_cast<size_t>(slice));
        SM_RETURN_IF_ERROR(inner_->ReadSlices(z, 1, buffer_));
        data = buffer_;
      }
      for (int64_t y = 0; y < info_.dims.ny; ++y) {
        const int64_t from = ((region_.lo.y + y) * full.nx + region_.lo.x) * bpv;
        std::memcpy(out.data() + k * out_slice + y * row, data.data() + from,
                    static_cast<size_t>(row));
      }
    }
    return absl::OkStatus();
  }
  // The inner slices its rows are cut from.
  std::optional<std::vector<FileRange>> BytesRead(int64_t z0, int64_t count) const override {
    return inner_->BytesRead(region_.lo.z + z0, count);
  }

 private:
  std::unique_ptr<VolumeSource> inner_;
  const VoxelRegion region_;
  std::vector<std::byte> buffer_;  // one slice of the inner volume, where it cannot map
};

// The dims a file name gives, and its type token if it has one ("_u8", "_i7").
struct NamedDims {
  Dims dims;
  std::string type_token;
};

std::optional<NamedDims> ParseNamedDims(const std::string& path) {
  // The dims, then maybe a type token: a letter or two and a bit count.
  static const std::regex kPattern(R"((\d+)x(\d+)x(\d+)(?:_([a-z]+\d+)(?![a-z0-9]))?)",
                                   std::regex::icase);
  const std::string name = std::filesystem::path(path).filename().string();
  std::smatch m;
  if (!std::regex_search(name, m, kPattern)) return std::nullopt;
  NamedDims n;
  if (!absl::SimpleAtoi(m[1].str(), &n.dims.nx) || !absl::SimpleAtoi(m[2].str(), &n.dims.ny) ||
      !absl::SimpleAtoi(m[3].str(), &n.dims.nz)) {
    return std::nullopt;
  }
  if (m[4].matched) n.type_token = m[4].str();
  return n;
}

absl::StatusOr<DType> TypeOfToken(const std::string& path, const std::string& token) {
  if (token.empty()) return DType::kUInt8;
  const std::string t = absl::AsciiStrToLower(token);
  absl::StatusOr<DType> parsed = ParseDType(t);
  if (parsed.ok()) return parsed;
  if (t == "u8") return DType::kUInt8;
  if (t == "u16") return DType::kUInt16;
  if (t == "f32") return DType::kFloat32;
  return absl::InvalidArgumentError(
      absl::StrCat(path, ": the name gives the voxel type '", token,
                   "', which is not u8, u16 or f32 (give the type: --dtype, input.dtype)"));
}

}  // namespace

std::string VoxelRegion::ToString() const {
  return absl::StrCat(lo.x, ",", lo.y, ",", lo.z, ",", hi.x, ",", hi.y, ",", hi.z);
}

absl::StatusOr<std::unique_ptr<VolumeSource>> OpenRegion(std::unique_ptr<VolumeSource> source,
                                                         const VoxelRegion& region) {
  const Dims& d = source->info().dims;
  const int64_t lo[3] = {region.lo.x, region.lo.y, region.lo.z};
  const int64_t hi[3] = {region.hi.x, region.hi.y, region.hi.z};
  const int64_t n[3] = {d.nx, d.ny, d.nz};
  for (int k = 0; k < 3; ++k) {
    if (lo[k] < 0 || hi[k] <= lo[k] || hi[k] > n[k]) {
      return absl::InvalidArgumentError(
          absl::StrCat(source->info().path, ": input.region ", region.ToString(), " is ",
                       hi[k] <= lo[k] ? "empty" : "outside the volume", " along ",
                       std::string(1, "xyz"[k]), " (the volume is ", d.ToString(),
                       "; give X0,Y0,Z0,X1,Y1,Z1 with 0 <= X0 < X1 <= ", d.nx, ", ...)"));
    }
  }
  return std::make_unique<RegionSource>(std::move(source), region);
}

absl::StatusOr<std::optional<std::pair<Dims, DType>>> DimsFromFileName(const std::string& path) {
  const std::optional<NamedDims> named = ParseNamedDims(path);
  if (!named) return std::nullopt;
  SM_ASSIGN_OR_RETURN(const DType t, TypeOfToken(path, named->type_token));
  return std::make_pair(named->dims, t);
}

absl::StatusOr<std::string> InputFormatOf(const std::string& path, const OpenOptions& options) {
  std::string format = absl::AsciiStrToLower(options.format);
  if (!format.empty()) return format;
  std::error_code ec;
  const bool is_dir = std::filesystem::is_directory(path, ec);
  {  // by name
    const std::string ext = absl::AsciiStrToLower(std::filesystem::path(path).extension().string());
    const std::string name = absl::AsciiStrToLower(std::filesystem::path(path).filename().string());
    if (SplitHdf5Path(path) || HasHdf5Extension(path)) {
      format = "hdf5";
    } else if (ext == ".npy") {
      format = "npy";
    } else if (ext == ".mrc" || ext == ".map" || ext == ".ccp4" || ext == ".rec") {
      format = "mrc";
    } else if (ext == ".nii" || absl::EndsWith(name, ".nii.gz")) {
      format = "nifti";
    } else if (is_dir) {
      format = "folder";
    } else if (ext == ".raw" || ext == ".bin" || ext == ".dat" || ext == ".img") {
      format = "raw";
    } else if (ext == ".tif" || ext == ".tiff") {
      format = "tiff";
    } else if (ext == ".png") {
      format = "png";
    } else if (ext == ".jpg" || ext == ".jpeg") {
      format = "jpeg";
    } else if (ext == ".dcm") {
      format = "dicom";
    } else if (ext == ".nrrd" || ext == ".nhdr") {
      format = "nrrd";
    } else if (ext == ".vdb") {
      format = "vdb";
    } else if (options.raw_dims) {
      format = "raw";
    } else {
      return absl::InvalidArgumentError(
          absl::StrCat(path, ": cannot tell the format from the extension '", ext,
                       "'; use .raw/.tif/.png/.jpg/.dcm/.nrrd/.nhdr/.vdb/.npy/.mrc/.nii/.h5, a "
                       "folder of slices, or give the format "
                       "(raw needs dims)"));
    }
  }
  return format;
}

absl::StatusOr<std::unique_ptr<VolumeSource>> OpenVolume(const std::string& path,
                                                         const OpenOptions& options) {
  std::error_code ec;
  const bool is_dir = std::filesystem::is_directory(path, ec);
  // "scan.h5:/entry/data": a dataset inside an HDF5 file.
  const auto hdf5 = SplitHdf5Path(path);
  SM_ASSIGN_OR_RETURN(const std::string format, InputFormatOf(path, options));
  std::unique_ptr<VolumeSource> source;
  if (!options.child_reader.program.empty() && ReadByLibrary(format)) {
    SM_ASSIGN_OR_RETURN(source, OpenVolumeInChild(path, format, options.vdb_grid, options.limits,
                                                  options.child_reader));
  } else if (format == "raw") {
    RawOptions raw;
    const std::optional<NamedDims> named = ParseNamedDims(path);
    if (options.raw_dims) {
      raw.dims = *options.raw_dims;
    } else if (named) {
      raw.dims = named->dims;
    } else {
      return absl::InvalidArgumentError(
          absl::StrCat(path,
                       ": a raw volume needs its dims (--dims NXxNYxNZ) or a name like "
                       "'rock_512x512x400_u8.raw'"));
    }
    // A type the name gives wrongly matters only when the type is not given otherwise.
    if (options.raw_dtype) {
      raw.dtype = *options.raw_dtype;
    } else {
      SM_ASSIGN_OR_RETURN(raw.dtype, TypeOfToken(path, named ? named->type_token : ""));
    }
    raw.byte_order = options.raw_byte_order;
    raw.header_bytes = options.raw_header_bytes;
    SM_ASSIGN_OR_RETURN(source, OpenRawVolume(path, raw, options.limits));
  } else if (format == "folder" || (is_dir && (format == "tiff" || format == "png" ||
                                               format == "jpeg" || format == "dicom"))) {
    // A folder of slices: of the format given, or of whatever format its files are.
    if (!is_dir) {
      return absl::InvalidArgumentError(absl::StrCat(path, ": format 'folder' needs a folder"));
    }
    SM_ASSIGN_OR_RETURN(source,
                        OpenSliceFolderOf(path, format == "folder" ? "" : format, options.limits));
  } else if (format == "tiff") {
    SM_ASSIGN_OR_RETURN(source, OpenTiffVolume(path, options.limits));
  } else if (format == "png" || format == "jpeg" || format == "dicom") {
    SM_ASSIGN_OR_RETURN(source, OpenSingleSlice(path, format, options.limits));
  } else if (format == "nrrd") {
    SM_ASSIGN_OR_RETURN(source, OpenNrrdVolume(path, options.limits));
  } else if (format == "vdb") {
    SM_ASSIGN_OR_RETURN(source, OpenVdbVolume(path, options.vdb_grid, options.limits));
  } else if (format == "npy") {
    SM_ASSIGN_OR_RETURN(source, OpenNpyVolume(path, options.limits));
  } else if (format == "mrc") {
    SM_ASSIGN_OR_RETURN(source, OpenMrcVolume(path, options.limits));
  } else if (format == "nifti") {
    SM_ASSIGN_OR_RETURN(source, OpenNiftiVolume(path, options.limits));
  } else if (format == "hdf5") {
    SM_ASSIGN_OR_RETURN(source, OpenHdf5Volume(hdf5 ? hdf5->first : path, hdf5 ? hdf5->second : "",
                                               options.limits));
  } else {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": format '", options.format,
                     "' is not supported; use raw, tiff, png, jpeg, dicom, folder, nrrd, vdb, npy, "
                     "mrc, nifti or hdf5"));
  }
  if (options.spacing) {
    for (int k = 0; k < 3; ++k) {
      if (!((*options.spacing)[k] > 0)) {
        return absl::InvalidArgumentError(absl::StrCat(path, ": spacing component ", k, " = ",
                                                       (*options.spacing)[k], " must be positive"));
      }
    }
  }
  // Readers take a slice (or a slab of slices) at once: one slice must fit the budget.
  const VolumeInfo& got = source->info();
  SM_RETURN_IF_ERROR(CheckAllocation(got.dims.nx * got.dims.ny * BytesPerVoxel(got.dtype),
                                     options.limits,
                                     absl::StrCat(path, ": one slice of ", got.dims.ToString())));
  if (options.spacing || options.origin || !options.unit.empty()) {
    source = std::make_unique<PlacedSource>(std::move(source), options);
  }
  if (options.region) return OpenRegion(std::move(source), *options.region);
  return source;
}

DenseVolume DenseVolume::Zeros(const Dims& dims, DType dtype) {
  DenseVolume v;
  v.info.dims = dims;
  v.info.dtype = dtype;
  v.data.assign(static_cast<size_t>(dims.num_voxels()) * BytesPerVoxel(dtype), std::byte{0});
  return v;
}

double DenseVolume::At(int64_t x, int64_t y, int64_t z) const {
  const Dims& d = info.dims;
  const size_t i = static_cast<size_t>((z * d.ny + y) * d.nx + x);
  switch (info.dtype) {
    case DType::kUInt8:
      return as<uint8_t>()[i];
    case DType::kUInt16:
      return as<uint16_t>()[i];
    case DType::kFloat32:
      return as<float>()[i];
  }
  return 0;
}

void DenseVolume::Set(int64_t x, int64_t y, int64_t z, double value) {
  const Dims& d = info.dims;
  const size_t i = static_cast<size_t>((z * d.ny + y) * d.nx + x);
  switch (info.dtype) {
    case DType::kUInt8:
      as<uint8_t>()[i] = static_cast<uint8_t>(value);
      break;
    case DType::kUInt16:
      as<uint16_t>()[i] = static_cast<uint16_t>(value);
      break;
    case DType::kFloat32:
      as<float>()[i] = static_cast<float>(value);
      break;
  }
}

absl::StatusOr<DenseVolume> ReadDense(VolumeSource& source, int64_t max_bytes) {
  const VolumeInfo& info = source.info();
  const int64_t bytes = info.dims.num_voxels() * BytesPerVoxel(info.dtype);
  if (bytes > max_bytes) {
    return absl::ResourceExhaustedError(
        absl::StrCat(info.path, ": ", bytes, " bytes do not fit the dense limit of ", max_bytes));
  }
  DenseVolume v;
  v.info = info;
  v.data.resize(static_cast<size_t>(bytes));
  SM_RETURN_IF_ERROR(source.ReadSlices(0, info.dims.nz, v.data));
  return v;
}

absl::Status WriteDense(const DenseVolume& volume, VolumeSink& sink) {
  SM_RETURN_IF_ERROR(sink.WriteSlices(volume.info.dims.nz, volume.data));
  return sink.Finish();
}

absl::StatusOr<VolumeFormat> ParseVolumeFormat(absl::string_view name) {
  const std::string n = absl::AsciiStrToLower(name);
  if (n == "raw") return VolumeFormat::kRaw;
  if (n == "tiff" || n == "tif") return VolumeFormat::kTiff;
  if (n == "tiff-folder") return VolumeFormat::kTiffFolder;
  if (n == "nrrd") return VolumeFormat::kNrrd;
  if (n == "nrrd-gzip") return VolumeFormat::kNrrdGzip;
  if (n == "vdb") return VolumeFormat::kVdb;
  if (n == "hdf5" || n == "h5") return VolumeFormat::kHdf5;
  return absl::InvalidArgumentError(
      absl::StrCat("volume format '", name,
                   "' is not supported; use raw, tiff, tiff-folder, nrrd, "
                   "nrrd-gzip, vdb or hdf5"));
}

absl::StatusOr<VolumeFormat> OutputVolumeFormat(absl::string_view name, const std::string& path) {
  if (!name.empty()) return ParseVolumeFormat(name);
  const std::string ext = absl::AsciiStrToLower(std::filesystem::path(path).extension().string());
  if (ext == ".tif" || ext == ".tiff") return VolumeFormat::kTiff;
  if (ext == ".nrrd") return VolumeFormat::kNrrd;
  if (ext == ".vdb") return VolumeFormat::kVdb;
  if (ext == ".h5" || ext == ".hdf5") return VolumeFormat::kHdf5;
  return VolumeFormat::kRaw;
}

absl::StatusOr<std::unique_ptr<VolumeSink>> CreateVolumeWriter(const std::string& path,
                                                               const VolumeInfo& info,
                                                               VolumeFormat format) {
  switch (format) {
    case VolumeFormat::kRaw:
      return CreateRawWriter(path, info);
    case VolumeFormat::kTiff:
      return CreateTiffWriter(path, info);
    case VolumeFormat::kTiffFolder:
      return CreateTiffFolderWriter(path, info);
    case VolumeFormat::kNrrd:
      return CreateNrrdWriter(path, info, NrrdEncoding::kRaw);
    case VolumeFormat::kNrrdGzip:
      return CreateNrrdWriter(path, info, NrrdEncoding::kGzip);
    case VolumeFormat::kVdb:
      return CreateVdbWriter(path, info);
    case VolumeFormat::kHdf5:
      return CreateHdf5Writer(path, info);
  }
  return absl::InvalidArgumentError("unknown volume format");
}

}  // namespace sheetmesh
