#include "worker/pipeline/volume/hdf5_io.h"

#include <hdf5.h>

#include <cstring>
#include <filesystem>
#include <memory>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "common/paths.h"
#include "common/status_macros.h"
#include "worker/pipeline/volume/hdf5_internal.h"

namespace sheetmesh {
namespace {

using hdf5_internal::H5Id;
using hdf5_internal::QuietErrors;

// Deflate's best (1032:1 on constant data), with room for the chunk index.
constexpr double kMaxDeflateRatio = 1100;

// The most objects a listing visits, and the deepest path it descends: a file of 2,000
// nested groups took minutes to list in full (each name is opened from the root).
constexpr int kMaxListedObjects = 4096;
constexpr size_t kMaxListedNameBytes = 1024;

struct Listing {
  std::vector<std::string> names;
  int visited = 0;
  bool cut = false;  // the listing stopped at a bound
};

// The 2D and 3D numeric datasets of a file, for messages and for picking the only one;
// at most kMaxListedObjects objects are looked at.
Listing VolumeDatasets(hid_t file) {
  Listing listing;
  H5Ovisit(
      file, H5_INDEX_NAME, H5_ITER_NATIVE,
      [](hid_t obj, const char* name, const H5O_info_t* info, void* out) -> herr_t {
        auto* l = static_cast<Listing*>(out);
        if (++l->visited > kMaxListedObjects || std::strlen(name) > kMaxListedNameBytes) {
          l->cut = true;
          return 1;  // stops the visit
        }
        if (info->type != H5O_TYPE_DATASET) return 0;
        H5Id ds(H5Dopen2(obj, name, H5P_DEFAULT), H5Dclose);
        if (!ds.ok()) return 0;
        H5Id space(H5Dget_space(ds.get()), H5Sclose);
        H5Id type(H5Dget_type(ds.get()), H5Tclose);
        const int rank = H5Sget_simple_extent_ndims(space.get());
        const H5T_class_t c = H5Tget_class(type.get());
        if ((rank == 2 || rank == 3) && (c == H5T_INTEGER || c == H5T_FLOAT)) {
          l->names.push_back(absl::StrCat("/", name));
        }
        return 0;
      },
      &listing);
  return listing;
}

std::string Listed(const Listing& l) {
  if (l.names.empty()) return l.cut ? "none among the first objects" : "none";
  return absl::StrCat(absl::StrJoin(l.names, ", "),
                      l.cut ? " (and maybe more: the listing stops after 4096 objects)" : "");
}

// What a dataset may make the library read besides its own file: external raw storage,
// the source files of a virtual dataset, and external links on the way to it. A volume sent
// to the server (confine_named_files without roots) may name no other file; a referenced one
// only files under the roots.
struct NamedFilePolicy {
  std::string file;  // the HDF5 file, for messages and relative names
  VolumeLimits limits;
  absl::Status refused;  // set by the external-link callback when it denies a link
};

// The file `name` (as the HDF5 file `from` stores it) may be read, or the status saying why
// not. Relative names are taken beside `from` (the efile and virtual prefixes are set so).
absl::StatusOr<std::string> AllowNamedFile(const NamedFilePolicy& p, const std::string& from,
                                           const std::string& name, absl::string_view what) {
  std::filesystem::path path(name);
  if (path.is_relative()) path = std::filesystem::absolute(from).parent_path() / path;
  if (!p.limits.confine_named_files) return path.string();
  if (p.limits.named_file_roots.empty()) {
    return absl::PermissionDeniedError(absl::StrCat(
        p.file, ": ", what, " names the file '", name,
        "'; a volume sent to the server may not name another file (copy the data into the "
        "dataset, e.g. h5repack -l CONTI, or send the volume by reference under an allowed "
        "root)"));
  }
  return ResolveUnderRoots(path.string(), p.limits.named_file_roots,
                           absl::StrCat(p.file, ": ", what));
}

herr_t OnExternalLink(const char* parent_file, const char*, const char* child_file,
                      const char* child_object, unsigned*, hid_t, void* data) {
  auto* p = static_cast<NamedFilePolicy*>(data);
  absl::StatusOr<std::string> ok =
      AllowNamedFile(*p, parent_file, child_file,
                     absl::StrCat("an external link to ", child_file, ":", child_object));
  if (ok.ok()) return 0;
  if (p->refused.ok()) p->refused = ok.status();
  return -1;
}

// A dataset access list that resolves relative external names beside their file and asks
// `policy` before following an external link.
H5Id AccessList(NamedFilePolicy* policy) {
  H5Id dapl(H5Pcreate(H5P_DATASET_ACCESS), H5Pclose);
  H5Pset_efile_prefix(dapl.get(), "${ORIGIN}");
  H5Pset_elink_cb(dapl.get(), OnExternalLink, policy);
  return dapl;
}

// Refuses external raw storage and virtual sources that `policy` does not allow; `depth`
// counts virtual datasets followed (one level: a source may not be virtual itself).
absl::Status CheckNamedStorage(NamedFilePolicy& policy, const std::string& file, hid_t ds,
                               const std::string& where, int depth) {
  H5Id dcpl(H5Dget_create_plist(ds), H5Pclose);
  if (!dcpl.ok()) return absl::InvalidArgumentError(absl::StrCat(where, ": no creation list"));
  const int externals = H5Pget_external_count(dcpl.get());
  for (int i = 0; i < externals; ++i) {
    char name[4096] = {0};
    off_t offset = 0;
    hsize_t size = 0;
    if (H5Pget_external(dcpl.get(), i, sizeof(name), name, &offset, &size) < 0) {
      return absl::InvalidArgumentError(
          absl::StrCat(where, ": external storage entry ", i, " cannot be read"));
    }
    SM_RETURN_IF_ERROR(
        AllowNamedFile(policy, file, name, absl::StrCat("dataset ", where, " (external storage)"))
            .status());
  }
  if (H5Pget_layout(dcpl.get()) != H5D_VIRTUAL) return absl::OkStatus();
  if (depth > 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(where, ": a virtual dataset whose source is virtual too is not read"));
  }
  size_t sources = 0;
  if (H5Pget_virtual_count(dcpl.get(), &sources) < 0) {
    return absl::InvalidArgumentError(absl::StrCat(where, ": its virtual mapping cannot be read"));
  }
  for (size_t i = 0; i < sources; ++i) {
    char name[4096] = {0}, dataset[4096] = {0};
    if (H5Pget_virtual_filename(dcpl.get(), i, name, sizeof(name)) < 0 ||
        H5Pget_virtual_dsetname(dcpl.get(), i, dataset, sizeof(dataset)) < 0) {
      return absl::InvalidArgumentError(
          absl::StrCat(where, ": virtual source ", i, " cannot be read"));
    }
    if (std::string(name) == ".") continue;  // this file: its own checks apply
    if (std::strchr(name, '%') != nullptr || std::strchr(dataset, '%') != nullptr) {
      return absl::InvalidArgumentError(absl::StrCat(where, ": virtual source '", name, ":",
                                                     dataset, "' is a pattern; not read"));
    }
    SM_ASSIGN_OR_RETURN(
        const std::string source,
        AllowNamedFile(policy, file, name,
                       absl::StrCat("virtual dataset ", where, " (source ", i, ")")));
    H5Id sf(H5Fopen(source.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
    if (!sf.ok()) continue;  // a missing source reads as fill values
    H5Id dapl = AccessList(&policy);
    H5Id sds(H5Dopen2(sf.get(), dataset, dapl.get()), H5Dclose);
    SM_RETURN_IF_ERROR(policy.refused);
    if (!sds.ok()) continue;
    SM_RETURN_IF_ERROR(CheckNamedStorage(policy, source, sds.get(),
                                         absl::StrCat(source, ":", dataset), depth + 1));
  }
  return absl::OkStatus();
}

// Refuses chunk sizes and compression that would make a small file cost gigabytes or minutes:
// a chunk is decoded whole, so it must fit the budget and not exceed the dataset by much,
// and the data may not decode to more than deflate's best ratio allows.
absl::Status CheckStorageCost(hid_t ds, hid_t file_type, int64_t declared_bytes,
                              const VolumeLimits& limits, const std::string& where) {
  H5Id dcpl(H5Dget_create_plist(ds), H5Pclose);
  const size_t type_bytes = H5Tget_size(file_type);
  if (H5Pget_layout(dcpl.get()) == H5D_CHUNKED) {
    hsize_t chunk[H5S_MAX_RANK] = {0};
    const int rank = H5Pget_chunk(dcpl.get(), H5S_MAX_RANK, chunk);
    int64_t bytes = static_cast<int64_t>(type_bytes);
    std::string shape;
    for (int k = 0; k < rank; ++k) {
      if (chunk[k] == 0 || bytes > (int64_t{1} << 50) / static_cast<int64_t>(chunk[k])) {
        return absl::InvalidArgumentError(absl::StrCat(where, ": chunk extent ", chunk[k]));
      }
      bytes *= static_cast<int64_t>(chunk[k]);
      absl::StrAppend(&shape, k ? "x" : "", chunk[k]);
    }
    SM_RETURN_IF_ERROR(
        CheckAllocation(bytes, limits, absl::StrCat(where, ": one chunk (", shape, ")")));
    // A chunk may be wider than a small dataset, but not by orders of magnitude.
    const int64_t allowed = std::max<int64_t>(int64_t{64} << 20, 8 * declared_bytes);
    if (bytes > allowed) {
      return absl::InvalidArgumentError(absl::StrCat(
          where, ": one chunk (", shape, ") holds ", bytes, " bytes for a dataset of ",
          declared_bytes, " bytes; rewrite it with smaller chunks (h5repack -l CHUNK=...)"));
    }
  }
  const H5D_layout_t layout = H5Pget_layout(dcpl.get());
  if (layout == H5D_VIRTUAL) return absl::OkStatus();
  const int64_t stored = static_cast<int64_t>(H5Dget_storage_size(ds));
  // Unfiltered contiguous or compact data is stored as it is read: a dataset holding fewer
  // bytes than its dims declare is damaged (libhdf5 1.10 reads past a short compact buffer).
  if ((layout == H5D_COMPACT || layout == H5D_CONTIGUOUS) &&
      H5Pget_external_count(dcpl.get()) == 0 && stored < declared_bytes) {
    return absl::InvalidArgumentError(absl::StrCat(where, ": declares ", declared_bytes,
                                                   " bytes of voxels but stores ", stored,
                                                   " (a damaged or cut file)"));
  }
  // In the file that holds the dataset (an external link's target, perhaps).
  hsize_t file_bytes = 0;
  {
    H5Id own(H5Iget_file_id(ds), H5Fclose);
    if (!own.ok() || H5Fget_filesize(own.get(), &file_bytes) < 0) file_bytes = 0;
  }
  if (layout == H5D_CONTIGUOUS && H5Pget_external_count(dcpl.get()) == 0 && stored > 0 &&
      file_bytes > 0) {
    const haddr_t at = H5Dget_offset(ds);
    if (at == HADDR_UNDEF || static_cast<int64_t>(at) + stored > static_cast<int64_t>(file_bytes)) {
      return absl::InvalidArgumentError(absl::StrCat(where, ": its data lies beyond the file's ",
                                                     file_bytes, " bytes (cut short?)"));
    }
  }
  // Deflate decodes at most 1032 bytes per stored byte; unwritten chunks read as the fill
  // value without any storage.
  return CheckCompressionRatio(declared_bytes, stored, kMaxDeflateRatio, where);
}

class Hdf5Source : public VolumeSource {
 public:
  Hdf5Source(hid_t file, hid_t dataset, hid_t memtype, int rank, VolumeInfo info,
             std::unique_ptr<NamedFilePolicy> policy)
      : policy_(std::move(policy)),
        file_(file, H5Fclose),
        ds_(dataset, H5Dclose),
        memtype_(memtype),
        rank_(rank) {
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
  std::unique_ptr<NamedFilePolicy> policy_;  // outlives the ids whose access list names it
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

// A short fixed-length string attribute on `obj` (at most 16 bytes, as the writer puts a
// length unit), or empty.
std::string StringAttribute(hid_t obj, const char* name) {
  if (H5Aexists(obj, name) <= 0) return {};
  H5Id attr(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
  H5Id type(H5Aget_type(attr.get()), H5Tclose);
  if (!type.ok() || H5Tget_class(type.get()) != H5T_STRING || H5Tis_variable_str(type.get()) > 0) {
    return {};
  }
  const size_t size = H5Tget_size(type.get());
  if (size == 0 || size > 16) return {};
  std::string v(size, '\0');
  if (H5Aread(attr.get(), type.get(), v.data()) < 0) return {};
  v.resize(std::strlen(v.c_str()));
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
  // The source keeps the policy: the access list's external-link callback points at it.
  auto policy = std::make_unique<NamedFilePolicy>();
  policy->file = file;
  policy->limits = limits;
  H5Id dapl = AccessList(policy.get());
  std::string name = dataset;
  if (name.empty()) {
    const Listing volumes = VolumeDatasets(fid);
    if (volumes.names.size() != 1 || volumes.cut) {
      return absl::InvalidArgumentError(absl::StrCat(
          file, ": name the dataset (", file, ":/path); the file has ", volumes.names.size(),
          volumes.cut ? " or more" : "", " 2D/3D datasets: ", Listed(volumes)));
    }
    name = volumes.names[0];
  }
  const std::string where = absl::StrCat(file, ":", name);
  const htri_t exists = H5Lexists(fid, name.c_str(), dapl.get());
  SM_RETURN_IF_ERROR(policy->refused);
  if (exists <= 0) {
    return absl::NotFoundError(absl::StrCat(where, ": the file has no dataset ", name,
                                            "; its 2D/3D datasets: ", Listed(VolumeDatasets(fid))));
  }
  const hid_t ds = H5Dopen2(fid, name.c_str(), dapl.get());
  SM_RETURN_IF_ERROR(policy->refused);
  if (ds < 0) return absl::InvalidArgumentError(absl::StrCat(where, ": is not a dataset"));
  H5Id ds_guard(ds, H5Dclose);
  SM_RETURN_IF_ERROR(CheckNamedStorage(*policy, file, ds, where, 0));
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
  SM_RETURN_IF_ERROR(CheckStorageCost(
      ds, type.get(), info.dims.num_voxels() * static_cast<int64_t>(size), limits, where));
  // "spacing" with its "unit" as this project writes them; else ImageJ's and ilastik's
  // "element_size_um"; else "spacing" alone.
  const std::vector<double> sp = FloatAttribute(ds, "spacing", 3);
  const std::string unit = StringAttribute(ds, "unit");
  if (!sp.empty() && !unit.empty()) {
    info.placement.spacing = {sp[0], sp[1], sp[2]};
    info.placement.unit = unit;
  } else if (auto um = FloatAttribute(ds, "element_size_um", 3); !um.empty()) {
    info.placement.spacing = {um[2], um[1], um[0]};
    info.placement.unit = "um";
  } else if (!sp.empty()) {
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
                                      std::move(info), std::move(policy));
}

}  // namespace sheetmesh
