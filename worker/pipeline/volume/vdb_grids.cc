#include "worker/pipeline/volume/vdb_grids.h"

#include <cerrno>
#include <cstdio>
#include <mutex>

#include "absl/strings/str_cat.h"
#include "common/file_util.h"

namespace sheetmesh {

void InitializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

openvdb::math::Transform::Ptr MakeTransform(const Placement& p) {
  openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
  m.setToScale(openvdb::Vec3d(p.spacing.x, p.spacing.y, p.spacing.z));
  m.setTranslation(openvdb::Vec3d(p.origin.x, p.origin.y, p.origin.z));
  return openvdb::math::Transform::createLinearTransform(m);
}

void SetVolumeMeta(openvdb::GridBase& grid, const Dims& dims, DType dtype, const Placement& p) {
  grid.insertMeta(kDimsMeta, openvdb::Vec3IMetadata(openvdb::Vec3i(
                                 static_cast<int>(dims.nx), static_cast<int>(dims.ny),
                                 static_cast<int>(dims.nz))));
  grid.insertMeta(kDTypeMeta, openvdb::StringMetadata(std::string(DTypeName(dtype))));
  if (!p.unit.empty()) grid.insertMeta(kUnitMeta, openvdb::StringMetadata(p.unit));
  grid.setTransform(MakeTransform(p));
}

absl::Status WriteGridsAtomically(const std::string& path, const openvdb::GridPtrVec& grids) {
  const std::string part = path + ".part";
  try {
    openvdb::io::File file(part);
    file.write(grids);
    file.close();
  } catch (const openvdb::Exception& e) {
    std::remove(part.c_str());
    return absl::InternalError(absl::StrCat(path, ": OpenVDB could not write: ", e.what()));
  } catch (const std::exception& e) {
    std::remove(part.c_str());
    return absl::InternalError(absl::StrCat(path, ": could not write: ", e.what()));
  }
  if (std::rename(part.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::remove(part.c_str());
    return ErrnoStatus(err, path);
  }
  return absl::OkStatus();
}

}  // namespace sheetmesh
