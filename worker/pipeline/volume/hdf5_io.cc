#include "worker/pipeline/volume/hdf5_io.h"

#include <hdf5.h>

#include <filesystem>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "common/status_macros.h"

namespace sheetmesh {
namespace {

// An HDF5 id closed by `close` on destruction.
class H5Id {
 public:
  H5Id(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  H5Id(const H5Id&) = delete;
  H5Id& operator=(const H5Id&) = delete;
  ~H5Id() {
    if (id_ >= 0) close_(id_);
  }
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }
  // Gives the id up: it is no longer closed here.
  hid_t release() {
    const hid_t id = id_;
    id_ = -1;
    return id;
  }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

void QuietErrors() { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }

// The 2D and 3D numeric datasets of a file, for messages and for picking the only one.
std::vector<std::string> VolumeDatasets(hid_t file) {
  std::vector<std::string> names;
  H5Ovisit(
      file, H5_INDEX_NAME, H5_ITER_NATIVE,
      [](hid_t obj, const char* name, const H5O_info_t* info, void* out) -> herr_t {
        if (info->type != H5O_TYPE_DATASET) return 0;
        H5Id ds(H5Dopen2(obj, name, H5P_DEFAULT), H5Dclose);
        if (!ds.ok()) return 0;
        H5Id space(H5Dget_space(ds.get()), H5Sclose);
        H5Id type(H5Dget_type(ds.get()), H5Tclose);
        const int rank = H5Sget_simple_extent_ndims(space.get());
        const H5T_class_t c = H5Tget_class(type.get());
        if ((rank == 2 || rank == 3) && (c == H5T_INTEGER || c == H5T_FLOAT)) {
          static_cast<std::vector<std::string>*>(out)->push_back(absl::StrCat("/", name));
        }
        return 0;
      },
      &names);
  return names;
}

class Hdf5Source : public VolumeSource {
 public:
  Hdf5Source(hid_t file, hid_t dataset, hid_t memtype, int rank, VolumeInfo info)
      : file_(file, H5Fclose), ds_(dataset, H5Dclose), memtype_(memtype), rank_(rank) {
    info_ = std::move(info);
  }

  absl::Status ReadSlices(int64_t z0, int64_t count, std::span<std::byte> out) override {
    const Dims& d = info_.dims;
    SM_RETURN_IF_ERROR(CheckSliceRequest(z0, count, out.size()));
    if (count == 0) return absl::OkStatus();
    H5Id space(H5Dget_space(ds_.get()), H5Sclose);
    hsize_t start[3] = {static_cast<hsize_t>(z0), 0, 0};
    hsize_t extent[3] = {static_cast<hsize_t>(count), static_cast<hsize_t>(d.ny),
                         static_cast<hsize_t>(d.nx)};
    hsize_t* s = rank_ == 3 ? start : start + 1;
    hsize_t* e = rank_ == 3 ? extent : extent + 1;
    if (H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, s, nullptr, e, nullptr) < 0) {
      return absl::InternalError(absl::StrCat(info_.path, ": HDF5 cannot select slices ", z0));
    }
    H5Id mem(H5Screate_simple(rank_, e, nullptr), H5Sclose);
    if (H5Dread(ds_.get(), memtype_, mem.get(), space.get(), H5P_DEFAULT, out.data()) < 0) {
      return absl::InvalidArgumentError(
          absl::StrCat(info_.path, ": slices ", z0, "..", z0 + count - 1,
                       " cannot be read (a damaged chunk, or a filter this HDF5 library lacks)"));
    }
    return absl::OkStatus();
  }

 private:
  H5Id file_, ds_;
  hid_t memtype_;
  int rank_;
};

// A float attribute of `n` values on `obj`, or empty.
std::vector<double> FloatAttribute(hid_t obj, const char* name, int n) {
  if (H5Aexists(obj, name) <= 0) return {};
  H5Id attr(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
  H5Id space(H5Aget_space(attr.get()), H5Sclose);
  if (H5Sget_simple_extent_npoints(space.get()) != n) return {};
  std::vector<double> v(n);
  if (H5Aread(attr.get(), H5T_NATIVE_DOUBLE, v.data()) < 0) return {};
  return v;
}

}  // namespace

bool HasHdf5Extension(const std::string& path) {
  const std::string ext = absl::AsciiStrToLower(std::filesystem::path(path).extension().string());
  return ext == ".h5" || ext == ".hdf5" || ext == ".hdf" || ext == ".he5" || ext == ".nxs";
}

std::optional<std::pair<std::string, std::string>> SplitHdf5Path(const std::string& path) {
  const size_t colon = path.rfind(':');
  if (colon == std::string::npos || colon + 1 >= path.size() || path[colon + 1] != '/') {
    return std::nullopt;
  }
  const std::string file = path.substr(0, colon);
  if (!HasHdf5Extension(file)) return std::nullopt;
  return std::make_pair(file, path.substr(colon + 1));
}

absl::StatusOr<std::unique_ptr<VolumeSource>> OpenHdf5Volume(const std::string& file,
                                                             const std::string& dataset,
                                                             const VolumeLimits& limits) {
  QuietErrors();
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) {
    return absl::NotFoundError(absl::StrCat(file, ": no such file"));
  }
  if (H5Fis_hdf5(file.c_str()) <= 0) {
    return absl::InvalidArgumentError(absl::StrCat(file, ": not an HDF5 file"));
  }
  const hid_t fid = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (fid < 0) return absl::InvalidArgumentError(absl::StrCat(file, ": HDF5 cannot open it"));
  H5Id guard(fid, H5Fclose);
  const std::vector<std::string> volumes = VolumeDatasets(fid);
  std::string name = dataset;
  if (name.empty()) {
    if (volumes.size() != 1) {
      return absl::InvalidArgumentError(
          absl::StrCat(file, ": name the dataset (", file, ":/path); the file has ", volumes.size(),
                       " 2D/3D datasets: ", absl::StrJoin(volumes, ", ")));
    }
    name = volumes[0];
  }
  const std::string where = absl::StrCat(file, ":", name);
  if (H5Lexists(fid, name.c_str(), H5P_DEFAULT) <= 0) {
    return absl::NotFoundError(absl::StrCat(
        where, ": the file has no dataset ", name,
        "; its 2D/3D datasets: ", volumes.empty() ? "none" : absl::StrJoin(volumes, ", ")));
  }
  const hid_t ds = H5Dopen2(fid, name.c_str(), H5P_DEFAULT);
  if (ds < 0) return absl::InvalidArgumentError(absl::StrCat(where, ": is not a dataset"));
  H5Id ds_guard(ds, H5Dclose);
  H5Id space(H5Dget_space(ds), H5Sclose);
  H5Id type(H5Dget_type(ds), H5Tclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank != 2 && rank != 3) {
    return absl::InvalidArgumentError(
        absl::StrCat(where, ": rank ", rank, " is not 2 or 3 (a volume is z, y, x)"));
  }
  hsize_t ext[3] = {1, 1, 1};
  H5Sget_simple_extent_dims(space.get(), rank == 3 ? ext : ext + 1, nullptr);
  const H5T_class_t cls = H5Tget_class(type.get());
  if (cls != H5T_INTEGER && cls != H5T_FLOAT) {
    return absl::InvalidArgumentError(
        absl::StrCat(where, ": its type is not an integer or a float"));
  }
  VolumeInfo info;
  info.path = where;
  info.format = "hdf5";
  info.dims = {static_cast<int64_t>(ext[2]), static_cast<int64_t>(ext[1]),
               static_cast<int64_t>(ext[0])};
  const size_t size = H5Tget_size(type.get());
  const bool is_unsigned = cls == H5T_INTEGER && H5Tget_sign(type.get()) == H5T_SGN_NONE;
  hid_t memtype = H5T_NATIVE_FLOAT;
  info.dtype = DType::kFloat32;
  if (cls == H5T_INTEGER && is_unsigned && size == 1) {
    memtype = H5T_NATIVE_UINT8;
    info.dtype = DType::kUInt8;
  } else if (cls == H5T_INTEGER && is_unsigned && size == 2) {
    memtype = H5T_NATIVE_UINT16;
    info.dtype = DType::kUInt16;
  } else if (!(cls == H5T_FLOAT && size == 4)) {
    info.format = absl::StrCat("hdf5 ",
                               cls == H5T_FLOAT ? "float"
                               : is_unsigned    ? "uint"
                                                : "int",
                               size * 8, "→float32");
  }
  SM_RETURN_IF_ERROR(CheckDims(info.dims, info.dtype, limits, where));
  if (auto um = FloatAttribute(ds, "element_size_um", 3); !um.empty()) {
    info.placement.spacing = {um[2], um[1], um[0]};
    info.placement.unit = "um";
  } else if (auto sp = FloatAttribute(ds, "spacing", 3); !sp.empty()) {
    info.placement.spacing = {sp[0], sp[1], sp[2]};
  }
  for (int k = 0; k < 3; ++k) {
    if (!(info.placement.spacing[k] > 0)) {
      return absl::InvalidArgumentError(absl::StrCat(where, ": spacing attribute component ", k,
                                                     " = ", info.placement.spacing[k],
                                                     " is not positive"));
    }
  }
  return std::make_unique<Hdf5Source>(guard.release(), ds_guard.release(), memtype, rank,
                                      std::move(info));
}

}  // namespace sheetmesh
