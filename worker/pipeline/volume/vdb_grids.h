// Internal to the OpenVDB adapters (volume/vdb_io.cc, voxel/voxel_set_vdb.cc): the
// metadata sheetmesh keeps on its grids and an atomic grid writer. Includes OpenVDB: never
// include it from a public header.
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_VDB_GRIDS_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_VDB_GRIDS_H_

#include <openvdb/openvdb.h>

#include <string>

#include "absl/status/status.h"
#include "common/types.h"
#include "worker/pipeline/volume/volume_source.h"

namespace sheetmesh {

inline constexpr char kDimsMeta[] = "sheetmesh_dims";
inline constexpr char kDTypeMeta[] = "sheetmesh_dtype";
inline constexpr char kUnitMeta[] = "sheetmesh_unit";

// openvdb::initialize(), once per process. Thread-safe.
void InitializeOpenVdb();

// The index-to-world transform of `p` (scale by spacing, then translate by origin).
openvdb::math::Transform::Ptr MakeTransform(const Placement& p);

// Records dims, dtype and unit on `grid` and gives it `p`'s transform.
void SetVolumeMeta(openvdb::GridBase& grid, const Dims& dims, DType dtype, const Placement& p);

// Writes `grids` to `path` through a `.part` file and a rename. kInternal when OpenVDB
// fails; the errno's status when the rename does. Leaves no `.part` behind.
absl::Status WriteGridsAtomically(const std::string& path, const openvdb::GridPtrVec& grids);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_VDB_GRIDS_H_
