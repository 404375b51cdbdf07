// Chunked, compressed HDF5 volumes written slice by slice (hdf5_io.h).
#include <hdf5.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "worker/pipeline/volume/hdf5_internal.h"
#include "worker/pipeline/volume/hdf5_io.h"

namespace sheetmesh {
namespace {

using hdf5_internal::H5Id;
using hdf5_internal::QuietErrors;

// Chunks of up to kChunk[0] slices by kChunk[1] rows by kChunk[2] columns, shuffled and
// deflated: a label volume that is mostly zeros takes a few bytes a chunk, and a reader
// takes any brick without the rest.
constexpr hsize_t kChunk[3] = {8, 128, 128};

// The type of `dtype` in the file (little-endian, as written everywhere) and in memory.
struct Types {
  hid_t file, memory;
};
Types TypesOf(DType dtype) {
  if (dtype == DType::kUInt16) return {H5T_STD_U16LE, H5T_NATIVE_UINT16};
  if (dtype == DType::kFloat32) return {H5T_IEEE_F32LE, H5T_NATIVE_FLOAT};
  return {H5T_STD_U8LE, H5T_NATIVE_UINT8};
}

// Micrometres per `unit`, 0 where the unit is not a length this knows.
double Micrometres(const std::string& unit) {
  if (unit == "um" || unit == "µm") return 1;
  if (unit == "mm") return 1e3;
  if (unit == "nm") return 1e-3;
  if (unit == "m") return 1e6;
  return 0;
}

class Hdf5Sink : public VolumeSink {
 public:
  Hdf5Sink(std::string path, std::string part, H5Id file, H5Id dataset, VolumeInfo info)
      : path_(std::move(path)),
        part_(std::move(part)),
        file_(std::move(file)),
        dataset_(std::move(dataset)) {
    info_ = std::move(info);
  }
  ~Hdf5Sink() override {
    if (!committed_) {
      if (dataset_.ok()) H5Dclose(dataset_.release());
      if (file_.ok()) H5Fclose(file_.release());
      std::error_code ec;
      std::filesystem::remove(part_, ec);
    }
  }

  absl::Status WriteSlices(int64_t count, std::span<const std::byte> data) override {
    const int64_t z0 = slices_written_;
    SM_RETURN_IF_ERROR(Advance(count, data.size()));
    if (count == 0) return absl::OkStatus();
    const Dims& d = info_.dims;
    const hsize_t start[3] = {static_cast<hsize_t>(z0), 0, 0};
    const hsize_t size[3] = {static_cast<hsize_t>(count), static_cast<hsize_t>(d.ny),
                             static_cast<hsize_t>(d.nx)};
    H5Id space(H5Dget_space(dataset_.get()), H5Sclose);
    H5Id memory(H5Screate_simple(3, size, nullptr), H5Sclose);
    if (!space.ok() || !memory.ok() ||
        H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start, nullptr, size, nullptr) < 0 ||
        H5Dwrite(dataset_.get(), TypesOf(info_.dtype).memory, memory.get(), space.get(),
                 H5P_DEFAULT, data.data()) < 0) {
      return absl::InternalError(
          absl::StrCat(path_, ": HDF5 could not write slices ", z0, "–", z0 + count - 1));
    }
    return absl::OkStatus();
  }

  absl::Status Finish() override {
    SM_RETURN_IF_ERROR(CheckComplete());
    H5Dclose(dataset_.release());
    if (H5Fclose(file_.release()) < 0) {
      return absl::InternalError(absl::StrCat(path_, ": HDF5 could not close the file"));
    }
    std::error_code ec;
    std::filesystem::rename(part_, path_, ec);
    if (ec) return absl::InternalError(absl::StrCat(path_, ": ", ec.message()));
    committed_ = true;
    return absl::OkStatus();
  }

 private:
  std::string path_, part_;
  H5Id file_, dataset_;
  bool committed_ = false;
};

}  // namespace

absl::StatusOr<std::unique_ptr<VolumeSink>> CreateHdf5Writer(const std::string& path,
                                                             const VolumeInfo& info,
                                                             const std::string& dataset) {
  QuietErrors();
  const Dims& d = info.dims;
  if (d.nx <= 0 || d.ny <= 0 || d.nz <= 0) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": dims ", d.ToString(), " are empty"));
  }
  const std::string part = path + ".part";
  H5Id file(H5Fcreate(part.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
  if (!file.ok()) return absl::InternalError(absl::StrCat(path, ": HDF5 cannot create the file"));
  const hsize_t dims[3] = {static_cast<hsize_t>(d.nz), static_cast<hsize_t>(d.ny),
                           static_cast<hsize_t>(d.nx)};
  hsize_t chunk[3];
  for (int k = 0; k < 3; ++k) chunk[k] = std::min(dims[k], kChunk[k]);
  H5Id space(H5Screate_simple(3, dims, nullptr), H5Sclose);
  H5Id create(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  H5Id access(H5Pcreate(H5P_DATASET_ACCESS), H5Pclose);
  // A cache for one layer of chunks: slices written a few at a time fill each chunk in
  // memory before it is compressed.
  const size_t layer = static_cast<size_t>(chunk[0]) * d.ny * d.nx * BytesPerVoxel(info.dtype);
  if (!space.ok() || !create.ok() || !access.ok() || H5Pset_chunk(create.get(), 3, chunk) < 0 ||
      H5Pset_shuffle(create.get()) < 0 || H5Pset_deflate(create.get(), 4) < 0 ||
      H5Pset_chunk_cache(access.get(), 100003, layer + (size_t{1} << 20), 1.0) < 0) {
    H5Fclose(file.release());
    std::filesystem::remove(part);
    return absl::InternalError(absl::StrCat(path, ": HDF5 cannot set up a chunked dataset"));
  }
  const std::string name = dataset.empty() ? "volume" : dataset;
  H5Id ds(H5Dcreate2(file.get(), name.c_str(), TypesOf(info.dtype).file, space.get(), H5P_DEFAULT,
                     create.get(), access.get()),
          H5Dclose);
  if (!ds.ok()) {
    H5Fclose(file.release());
    std::filesystem::remove(part);
    return absl::InternalError(absl::StrCat(path, ": HDF5 cannot create dataset ", name));
  }
  // The spacing as the reader takes it: "spacing" (x, y, z) always, and "element_size_um"
  // (z, y, x) where the unit is a known length, so that the unit comes back too.
  const auto put = [&](const char* attr, const std::vector<double>& v) {
    const hsize_t n = v.size();
    H5Id aspace(H5Screate_simple(1, &n, nullptr), H5Sclose);
    H5Id a(H5Acreate2(ds.get(), attr, H5T_IEEE_F64LE, aspace.get(), H5P_DEFAULT, H5P_DEFAULT),
           H5Aclose);
    return a.ok() && H5Awrite(a.get(), H5T_NATIVE_DOUBLE, v.data()) >= 0;
  };
  const Vec3& s = info.placement.spacing;
  bool ok = put("spacing", {s.x, s.y, s.z});
  const std::string& unit = info.placement.unit;
  if (const double um = Micrometres(unit); um > 0) {
    ok = ok && put("element_size_um", {s.z * um, s.y * um, s.x * um});
  }
  if (!unit.empty() && unit.size() <= 16) {
    H5Id type(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Id scalar(H5Screate(H5S_SCALAR), H5Sclose);
    ok = ok && type.ok() && H5Tset_size(type.get(), unit.size()) >= 0;
    H5Id a(
        ok ? H5Acreate2(ds.get(), "unit", type.get(), scalar.get(), H5P_DEFAULT, H5P_DEFAULT) : -1,
        H5Aclose);
    ok = ok && a.ok() && H5Awrite(a.get(), type.get(), unit.data()) >= 0;
  }
  if (!ok) {
    H5Dclose(ds.release());
    H5Fclose(file.release());
    std::filesystem::remove(part);
    return absl::InternalError(absl::StrCat(path, ": HDF5 cannot write the spacing"));
  }
  return std::make_unique<Hdf5Sink>(path, part, std::move(file), std::move(ds), info);
}

}  // namespace sheetmesh
