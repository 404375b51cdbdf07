#include "worker/pipeline/volume/vdb_io.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/excerpt.h"
#include "common/file_util.h"
#include "common/status_macros.h"

namespace sheetmesh {
namespace {

constexpr char kDimsMeta[] = "sheetmesh_dims";
constexpr char kDTypeMeta[] = "sheetmesh_dtype";
constexpr char kUnitMeta[] = "sheetmesh_unit";

// openvdb::initialize(), once per process.
void InitializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

constexpr char kSpacingMeta[] = "sheetmesh_spacing";
constexpr char kOriginMeta[] = "sheetmesh_origin";
constexpr char kTransformUnitMeta[] = "sheetmesh_transform_unit";

// OpenVDB refuses a transform whose determinant is nearly 0 (below about 1e-8): a voxel of
// 5 um given in metres. The transform is then written in a unit 1000^k smaller (the exact
// placement stays in the metadata, which this reader takes first).
double TransformScale(const Placement& p) {
  const double smallest = std::min({p.spacing.x, p.spacing.y, p.spacing.z});
  double scale = 1;
  while (smallest * scale < 1e-2 && scale < 1e15) scale *= 1000;
  return scale;
}

std::string ScaledUnit(const std::string& unit, double scale) {
  if (scale == 1) return unit;
  static const char* kLengths[] = {"m", "mm", "um", "nm", "pm"};
  int steps = static_cast<int>(std::lround(std::log10(scale) / 3));
  for (int i = 0; i < 5; ++i) {
    if (unit == kLengths[i] && i + steps < 5) return kLengths[i + steps];
  }
  return absl::StrCat(unit.empty() ? "unit" : unit, " x ", scale);
}

openvdb::math::Transform::Ptr MakeTransform(const Placement& p) {
  const double k = TransformScale(p);
  openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
  m.setToScale(openvdb::Vec3d(k * p.spacing.x, k * p.spacing.y, k * p.spacing.z));
  m.setTranslation(openvdb::Vec3d(k * p.origin.x, k * p.origin.y, k * p.origin.z));
  return openvdb::math::Transform::createLinearTransform(m);
}

void SetVolumeMeta(openvdb::GridBase& grid, const Dims& dims, DType dtype, const Placement& p) {
  grid.insertMeta(kDimsMeta, openvdb::Vec3IMetadata(openvdb::Vec3i(static_cast<int>(dims.nx),
                                                                   static_cast<int>(dims.ny),
                                                                   static_cast<int>(dims.nz))));
  grid.insertMeta(kDTypeMeta, openvdb::StringMetadata(std::string(DTypeName(dtype))));
  if (!p.unit.empty()) grid.insertMeta(kUnitMeta, openvdb::StringMetadata(p.unit));
  grid.insertMeta(kSpacingMeta,
                  openvdb::Vec3DMetadata(openvdb::Vec3d(p.spacing.x, p.spacing.y, p.spacing.z)));
  grid.insertMeta(kOriginMeta,
                  openvdb::Vec3DMetadata(openvdb::Vec3d(p.origin.x, p.origin.y, p.origin.z)));
  const double k = TransformScale(p);
  if (k != 1) grid.insertMeta(kTransformUnitMeta, openvdb::StringMetadata(ScaledUnit(p.unit, k)));
  grid.setTransform(MakeTransform(p));
}

// Writes `grids` to `path` through a `.part` file and a rename.
absl::Status WriteGridsAtomically(const std::string& path, const openvdb::GridPtrVec& grids) {
  const std::string part = path + ".part";
  try {
    openvdb::io::File file(part);
    file.write(grids);
    file.close();
  } catch (const openvdb::Exception& e) {
    std::remove(part.c_str());
    return absl::InternalError(
        absl::StrCat(path, ": OpenVDB could not write: ", Excerpt(e.what())));
  } catch (const std::exception& e) {
    std::remove(part.c_str());
    return absl::InternalError(absl::StrCat(path, ": could not write: ", Excerpt(e.what())));
  }
  if (std::rename(part.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::remove(part.c_str());
    return ErrnoStatus(err, path);
  }
  return absl::OkStatus();
}

// Walks the layout of a .vdb file (header, file metadata, grid descriptors) against its size
// before OpenVDB reads it: OpenVDB takes string lengths and offsets as they come, so a cut
// file made it allocate gigabytes from the bytes past the cut. Every length and offset must
// lie within the file. REQUIRES: nothing; reads at most the header and the descriptors.
class VdbLayout {
 public:
  VdbLayout(int fd, int64_t size, const std::string& path) : fd_(fd), size_(size), path_(path) {}

  absl::Status Check() {
    int64_t magic = 0;
    SM_RETURN_IF_ERROR(Read(&magic, "the magic number"));
    if (magic != openvdb::OPENVDB_MAGIC) return Bad("does not start with OpenVDB's magic number");
    uint32_t version = 0;
    SM_RETURN_IF_ERROR(Read(&version, "the file format version"));
    if (version < openvdb::OPENVDB_FILE_VERSION_ROOTNODE_MAP ||
        version > openvdb::OPENVDB_FILE_VERSION) {
      return Bad(absl::StrCat("file format version ", version, " is not one OpenVDB ",
                              OPENVDB_LIBRARY_VERSION_STRING, " reads (",
                              openvdb::OPENVDB_FILE_VERSION_ROOTNODE_MAP, "-",
                              openvdb::OPENVDB_FILE_VERSION, ")"));
    }
    SM_RETURN_IF_ERROR(Skip(8, "the library version"));
    char offsets = 0;
    SM_RETURN_IF_ERROR(Read(&offsets, "the grid-offsets flag"));
    if (offsets == 0) {
      return Bad("was written as a stream without grid offsets; save it with openvdb.write");
    }
    if (version >= openvdb::OPENVDB_FILE_VERSION_SELECTIVE_COMPRESSION &&
        version < openvdb::OPENVDB_FILE_VERSION_NODE_MASK_COMPRESSION) {
      SM_RETURN_IF_ERROR(Skip(1, "the compression flag"));
    }
    SM_RETURN_IF_ERROR(
        Skip(version >= openvdb::OPENVDB_FILE_VERSION_BOOST_UUID ? 36 : 16, "the file's UUID"));
    int32_t entries = 0;
    SM_RETURN_IF_ERROR(Read(&entries, "the file metadata count"));
    if (entries < 0 || entries > (size_ - at_) / 12) return Bad("its metadata count is corrupt");
    for (int32_t i = 0; i < entries; ++i) {
      SM_RETURN_IF_ERROR(String("a metadata name"));
      SM_RETURN_IF_ERROR(String("a metadata type"));
      SM_RETURN_IF_ERROR(String("a metadata value"));
    }
    int32_t grids = 0;
    SM_RETURN_IF_ERROR(Read(&grids, "the grid count"));
    if (grids < 0 || grids > (size_ - at_) / 36) return Bad("its grid count is corrupt");
    for (int32_t i = 0; i < grids; ++i) {
      const std::string what = absl::StrCat("grid descriptor ", i);
      SM_RETURN_IF_ERROR(String(what + "'s name"));
      SM_RETURN_IF_ERROR(String(what + "'s type"));
      if (version >= openvdb::OPENVDB_FILE_VERSION_GRID_INSTANCING) {
        SM_RETURN_IF_ERROR(String(what + "'s instance parent"));
      }
      int64_t grid = 0, block = 0, end = 0;
      SM_RETURN_IF_ERROR(Read(&grid, what));
      SM_RETURN_IF_ERROR(Read(&block, what));
      SM_RETURN_IF_ERROR(Read(&end, what));
      if (!(at_ <= grid && grid <= block && block <= end && end <= size_)) {
        return Bad(absl::StrCat(what, " places its grid at bytes ", grid, "-", end,
                                ", not within the file's ", size_, " (cut short?)"));
      }
      at_ = end;  // the next descriptor follows this grid's data
    }
    return absl::OkStatus();
  }

 private:
  absl::Status Bad(absl::string_view what) const {
    return absl::InvalidArgumentError(absl::StrCat(path_, ": not a readable .vdb: ", what));
  }
  absl::Status Skip(int64_t n, absl::string_view what) {
    if (n < 0 || n > size_ - at_) {
      return Bad(
          absl::StrCat("the file ends (at byte ", size_, ") within ", what, " (cut short?)"));
    }
    at_ += n;
    return absl::OkStatus();
  }
  template <class T>
  absl::Status Read(T* value, absl::string_view what) {
    const int64_t from = at_;
    SM_RETURN_IF_ERROR(Skip(sizeof(T), what));
    return ReadFullyAt(fd_, from, std::as_writable_bytes(std::span<T>(value, 1)), path_);
  }
  // A length-prefixed string, skipped.
  absl::Status String(absl::string_view what) {
    uint32_t length = 0;
    SM_RETURN_IF_ERROR(Read(&length, what));
    return Skip(length, what);
  }

  int fd_;
  int64_t size_;
  const std::string& path_;
  int64_t at_ = 0;
};

absl::Status CheckVdbLayout(const std::string& path) {
  SM_ASSIGN_OR_RETURN(ScopedFd fd, OpenForRead(path));
  SM_ASSIGN_OR_RETURN(const int64_t size, FileSizeOf(fd.get(), path));
  return AsInputError(VdbLayout(fd.get(), size, path).Check());
}

template <class GridT>
class VdbSource : public VolumeSource {
 public:
  VdbSource(typename GridT::ConstPtr grid, openvdb::Coord origin, VolumeInfo info)
      : grid_(std::move(grid)), origin_(origin) {
    info_ = std::move(info);
  }

  absl::Status ReadSlices(int64_t z0, int64_t count, std::span<std::byte> out) override {
    const Dims& d = info_.dims;
    SM_RETURN_IF_ERROR(CheckSliceRequest(z0, count, out.size()));
    const openvdb::CoordBBox bbox(
        origin_ + openvdb::Coord(0, 0, static_cast<int>(z0)),
        origin_ + openvdb::Coord(static_cast<int>(d.nx - 1), static_cast<int>(d.ny - 1),
                                 static_cast<int>(z0 + count - 1)));
    try {
      switch (info_.dtype) {
        case DType::kUInt8:
          Copy<uint8_t>(bbox, out);
          break;
        case DType::kUInt16:
          Copy<uint16_t>(bbox, out);
          break;
        case DType::kFloat32:
          Copy<float>(bbox, out);
          break;
      }
    } catch (const openvdb::Exception& e) {
      return absl::InvalidArgumentError(absl::StrCat(info_.path, ": OpenVDB: ", Excerpt(e.what())));
    } catch (const std::exception& e) {
      return absl::InvalidArgumentError(
          absl::StrCat(info_.path, ": OpenVDB failed: ", Excerpt(e.what())));
    }
    return absl::OkStatus();
  }

 private:
  template <class T>
  void Copy(const openvdb::CoordBBox& bbox, std::span<std::byte> out) {
    openvdb::tools::Dense<T, openvdb::tools::LayoutXYZ> dense(bbox,
                                                              reinterpret_cast<T*>(out.data()));
    dense.fill(static_cast<T>(grid_->background()));
    openvdb::tools::copyToDense(*grid_, dense);
  }

  typename GridT::ConstPtr grid_;
  openvdb::Coord origin_;
};

// Bool and mask grids read as 1 where active: a BoolGrid with their topology, true on.
template <class GridT>
openvdb::BoolGrid::ConstPtr ActiveAsTrue(const GridT& grid) {
  auto out = openvdb::BoolGrid::create(false);
  out->tree().topologyUnion(grid.tree());
  for (auto it = out->beginValueOn(); it; ++it) it.setValue(true);
  return out;
}

template <class GridT>
std::unique_ptr<VolumeSource> MakeSource(openvdb::GridBase::ConstPtr base, openvdb::Coord origin,
                                         VolumeInfo info) {
  return std::make_unique<VdbSource<GridT>>(openvdb::gridConstPtrCast<GridT>(base), origin,
                                            std::move(info));
}

class VdbSink : public VolumeSink {
 public:
  explicit VdbSink(VolumeInfo info) {
    info_ = std::move(info);
    if (info_.dtype == DType::kFloat32) {
      fgrid_ = openvdb::FloatGrid::create(0.0f);
    } else {
      igrid_ = openvdb::Int32Grid::create(0);
    }
  }

  absl::Status WriteSlices(int64_t count, std::span<const std::byte> data) override {
    const int64_t z0 = slices_written_;
    SM_RETURN_IF_ERROR(Advance(count, data.size()));
    const Dims& d = info_.dims;
    const openvdb::CoordBBox bbox(
        openvdb::Coord(0, 0, static_cast<int>(z0)),
        openvdb::Coord(static_cast<int>(d.nx - 1), static_cast<int>(d.ny - 1),
                       static_cast<int>(z0 + count - 1)));
    try {
      switch (info_.dtype) {
        case DType::kUInt8:
          From<uint8_t>(bbox, data, *igrid_);
          break;
        case DType::kUInt16:
          From<uint16_t>(bbox, data, *igrid_);
          break;
        case DType::kFloat32:
          From<float>(bbox, data, *fgrid_);
          break;
      }
    } catch (const openvdb::Exception& e) {
      return absl::InternalError(absl::StrCat(info_.path, ": OpenVDB: ", Excerpt(e.what())));
    } catch (const std::exception& e) {
      return absl::InternalError(absl::StrCat(info_.path, ": OpenVDB failed: ", Excerpt(e.what())));
    }
    return absl::OkStatus();
  }

  absl::Status Finish() override {
    SM_RETURN_IF_ERROR(CheckComplete());
    openvdb::GridBase::Ptr grid = fgrid_ ? openvdb::GridBase::Ptr(fgrid_) : igrid_;
    grid->setName("volume");
    SetVolumeMeta(*grid, info_.dims, info_.dtype, info_.placement);
    return WriteGridsAtomically(info_.path, {grid});
  }

 private:
  template <class T, class GridT>
  static void From(const openvdb::CoordBBox& bbox, std::span<const std::byte> data, GridT& grid) {
    // copyFromDense only reads, but Dense has no const-data constructor.
    openvdb::tools::Dense<T, openvdb::tools::LayoutXYZ> dense(
        bbox, const_cast<T*>(reinterpret_cast<const T*>(data.data())));
    openvdb::tools::copyFromDense(dense, grid, typename GridT::ValueType(0));
  }

  openvdb::FloatGrid::Ptr fgrid_;
  openvdb::Int32Grid::Ptr igrid_;
};

}  // namespace

absl::StatusOr<std::unique_ptr<VolumeSource>> OpenVdbVolume(const std::string& path,
                                                            const std::string& grid_name,
                                                            const VolumeLimits& limits) {
  InitializeOpenVdb();
  SM_RETURN_IF_ERROR(CheckVdbLayout(path));
  openvdb::GridBase::Ptr base;
  try {
    openvdb::io::File file(path);
    file.open(/*delayLoad=*/false);
    if (grid_name.empty()) {
      openvdb::GridPtrVecPtr grids = file.getGrids();
      for (const auto& g : *grids) {
        if (g->isType<openvdb::FloatGrid>() || g->isType<openvdb::DoubleGrid>() ||
            g->isType<openvdb::Int32Grid>() || g->isType<openvdb::Int64Grid>() ||
            g->isType<openvdb::BoolGrid>() || g->isType<openvdb::MaskGrid>()) {
          base = g;
          break;
        }
      }
      if (base == nullptr) {
        return absl::NotFoundError(absl::StrCat(path, ": holds no scalar grid"));
      }
    } else {
      if (!file.hasGrid(grid_name)) {
        return absl::NotFoundError(absl::StrCat(path, ": has no grid named '", grid_name, "'"));
      }
      base = file.readGrid(grid_name);
    }
    file.close();
  } catch (const openvdb::Exception& e) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": not a readable .vdb: ", Excerpt(e.what())));
  } catch (const std::bad_alloc&) {
    // A cut or corrupt file gives OpenVDB sizes from random bytes.
    return absl::InvalidArgumentError(
        absl::StrCat(path,
                     ": not a readable .vdb: it claims more data than memory holds (cut "
                     "short or corrupt?)"));
  } catch (const std::exception& e) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": not a readable .vdb: ", Excerpt(e.what())));
  }

  VolumeInfo info;
  info.path = path;
  info.format = "vdb";
  openvdb::Coord origin(0, 0, 0);
  const auto dims_meta = base->getMetadata<openvdb::Vec3IMetadata>(kDimsMeta);
  const auto dtype_meta = base->getMetadata<openvdb::StringMetadata>(kDTypeMeta);
  if (dims_meta) {
    const openvdb::Vec3i v = dims_meta->value();
    info.dims = {v.x(), v.y(), v.z()};
  } else {
    const openvdb::CoordBBox bbox = base->evalActiveVoxelBoundingBox();
    if (bbox.empty()) return absl::InvalidArgumentError(absl::StrCat(path, ": the grid is empty"));
    origin = bbox.min();
    info.dims = {bbox.dim().x(), bbox.dim().y(), bbox.dim().z()};
  }
  const bool mask = base->isType<openvdb::BoolGrid>() || base->isType<openvdb::MaskGrid>();
  if (dtype_meta && !mask) {
    SM_ASSIGN_OR_RETURN(info.dtype, ParseDType(dtype_meta->value()));
  } else {
    info.dtype = mask ? DType::kUInt8 : DType::kFloat32;
  }
  SM_RETURN_IF_ERROR(CheckDims(info.dims, info.dtype, limits, path));
  const openvdb::math::Transform& xf = base->constTransform();
  const openvdb::Vec3d vs = xf.voxelSize();
  const openvdb::Vec3d o = xf.indexToWorld(origin);
  info.placement.spacing = {vs.x(), vs.y(), vs.z()};
  info.placement.origin = {o.x(), o.y(), o.z()};
  // The exact placement this writer kept beside a transform it had to scale.
  const auto spacing_meta = base->getMetadata<openvdb::Vec3DMetadata>(kSpacingMeta);
  const auto origin_meta = base->getMetadata<openvdb::Vec3DMetadata>(kOriginMeta);
  if (spacing_meta && origin_meta && dims_meta) {
    const openvdb::Vec3d sp = spacing_meta->value(), og = origin_meta->value();
    info.placement.spacing = {sp.x(), sp.y(), sp.z()};
    info.placement.origin = {og.x(), og.y(), og.z()};
  }
  if (const auto unit = base->getMetadata<openvdb::StringMetadata>(kUnitMeta)) {
    info.placement.unit = unit->value();
  }
  if (base->isType<openvdb::FloatGrid>()) return MakeSource<openvdb::FloatGrid>(base, origin, info);
  if (base->isType<openvdb::DoubleGrid>())
    return MakeSource<openvdb::DoubleGrid>(base, origin, info);
  if (base->isType<openvdb::Int32Grid>()) return MakeSource<openvdb::Int32Grid>(base, origin, info);
  if (base->isType<openvdb::Int64Grid>()) return MakeSource<openvdb::Int64Grid>(base, origin, info);
  if (base->isType<openvdb::BoolGrid>()) {
    return MakeSource<openvdb::BoolGrid>(
        ActiveAsTrue(*openvdb::gridConstPtrCast<openvdb::BoolGrid>(base)), origin, info);
  }
  if (base->isType<openvdb::MaskGrid>()) {
    return MakeSource<openvdb::BoolGrid>(
        ActiveAsTrue(*openvdb::gridConstPtrCast<openvdb::MaskGrid>(base)), origin, info);
  }
  return absl::InvalidArgumentError(absl::StrCat(path, ": grid '", base->getName(), "' of type ",
                                                 base->valueType(), " is not a scalar grid"));
}

absl::StatusOr<std::unique_ptr<VolumeSink>> CreateVdbWriter(const std::string& path,
                                                            const VolumeInfo& info) {
  InitializeOpenVdb();
  VolumeInfo out = info;
  out.path = path;
  out.format = "vdb";
  return std::make_unique<VdbSink>(std::move(out));
}

absl::Status WriteSparseVdb(const std::string& path, const Dims& dims,
                            std::span<const SparseRun> runs, std::span<const int32_t> labels,
                            const Placement& placement, const std::string& grid_name) {
  InitializeOpenVdb();
  uint64_t voxels = 0;
  for (const SparseRun& r : runs) voxels += static_cast<uint64_t>(r.x1 - r.x0);
  if (!labels.empty() && labels.size() != voxels) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": ", labels.size(), " labels for ", voxels, " voxels"));
  }
  openvdb::GridPtrVec grids;
  try {
    // A BoolGrid and a FloatGrid (labels exact below 2^24): the grid types python3-openvdb
    // reads; it refuses a file with a MaskGrid or an Int32Grid in it altogether.
    auto mask = openvdb::BoolGrid::create(false);
    openvdb::FloatGrid::Ptr label_grid;
    if (!labels.empty()) label_grid = openvdb::FloatGrid::create(-1.0f);
    uint64_t first = 0;
    for (const SparseRun& run : runs) {
      mask->tree().sparseFill(openvdb::CoordBBox(openvdb::Coord(run.x0, run.y, run.z),
                                                 openvdb::Coord(run.x1 - 1, run.y, run.z)),
                              true, true);
      if (label_grid) {
        auto lacc = label_grid->getAccessor();
        for (int32_t x = run.x0; x < run.x1; ++x) {
          lacc.setValue(openvdb::Coord(x, run.y, run.z),
                        static_cast<float>(labels[first + (x - run.x0)]));
        }
      }
      first += static_cast<uint64_t>(run.x1 - run.x0);
    }
    mask->setName(grid_name);
    SetVolumeMeta(*mask, dims, DType::kUInt8, placement);
    grids.push_back(mask);
    if (label_grid) {
      label_grid->setName(grid_name + "_labels");
      SetVolumeMeta(*label_grid, dims, DType::kFloat32, placement);
      grids.push_back(label_grid);
    }
  } catch (const openvdb::Exception& e) {
    return absl::InternalError(absl::StrCat(path, ": OpenVDB: ", Excerpt(e.what())));
  } catch (const std::exception& e) {
    return absl::InternalError(absl::StrCat(path, ": OpenVDB failed: ", Excerpt(e.what())));
  }
  return WriteGridsAtomically(path, grids);
}

}  // namespace sheetmesh
