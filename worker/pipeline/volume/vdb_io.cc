#include "worker/pipeline/volume/vdb_io.h"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Dense.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "common/excerpt.h"
#include "common/file_util.h"
#include "common/status_macros.h"
#include "worker/pipeline/volume/vdb_check.h"

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

// The descriptor `grid_name` names (a grid's name, or its unique name "name[N]"), or the
// first scalar grid when it is empty. kNotFound naming the grids there are otherwise.
absl::StatusOr<size_t> ChooseGrid(const VdbFileLayout& layout, const std::string& grid_name,
                                  const std::string& path) {
  std::vector<std::string> names;
  for (size_t i = 0; i < layout.grids.size(); ++i) {
    const VdbGridEntry& g = layout.grids[i];
    const std::string shown = openvdb::io::GridDescriptor::nameAsString(g.name);
    names.push_back(absl::StrCat("'", Excerpt(shown, 64), "' (", Excerpt(g.type, 64), ")"));
    if (grid_name.empty()) {
      if (IsScalarVdbGridType(g.type)) return i;
      continue;
    }
    if (g.name == openvdb::io::GridDescriptor::stringAsUniqueName(grid_name) ||
        openvdb::io::GridDescriptor::stripSuffix(g.name) == grid_name) {
      return i;
    }
  }
  const std::string listed = names.empty() ? "no grid" : absl::StrJoin(names, ", ");
  if (grid_name.empty()) {
    return absl::NotFoundError(absl::StrCat(path, ": holds no scalar grid (it has ", listed, ")"));
  }
  return absl::NotFoundError(
      absl::StrCat(path, ": has no grid named '", Excerpt(grid_name, 64), "' (it has ", listed,
                   "); input.vdb_grid names one"));
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
  // OpenVDB believes every size it reads: the whole structure of the grid it will read is
  // checked first, against the file and the memory budget.
  SM_ASSIGN_OR_RETURN(const VdbFileLayout layout, ReadVdbLayout(path));
  SM_ASSIGN_OR_RETURN(const size_t chosen, ChooseGrid(layout, grid_name, path));
  SM_RETURN_IF_ERROR(CheckVdbGrid(path, layout, chosen, MemoryBudget(limits)));
  openvdb::GridBase::Ptr base;
  try {
    openvdb::io::File file(path);
    file.open(/*delayLoad=*/false);
    base = file.readGrid(layout.grids[chosen].name);
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
    absl::StatusOr<DType> dtype = ParseDType(dtype_meta->value());
    if (!dtype.ok()) {
      return absl::InvalidArgumentError(
          absl::StrCat(path, ": metadata ", kDTypeMeta, ": ", dtype.status().message()));
    }
    info.dtype = *dtype;
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
