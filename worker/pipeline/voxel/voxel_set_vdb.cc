#include "worker/pipeline/voxel/voxel_set_vdb.h"

#include <openvdb/openvdb.h>

#include "absl/strings/str_cat.h"
#include "worker/pipeline/volume/vdb_grids.h"

namespace sheetmesh {

absl::Status WriteVoxelSetVdb(const std::string& path, const VoxelSet& set,
                              std::span<const int32_t> labels, const Placement& placement,
                              const std::string& grid_name) {
  InitializeOpenVdb();
  if (!labels.empty() && labels.size() != set.size()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": ", labels.size(),
                                                   " labels for ", set.size(), " voxels"));
  }
  openvdb::GridPtrVec grids;
  try {
    auto mask = openvdb::MaskGrid::create();
    openvdb::Int32Grid::Ptr label_grid;
    if (!labels.empty()) label_grid = openvdb::Int32Grid::create(-1);
    set.ForEachRun([&](int32_t y, int32_t z, const Run& run, uint64_t first) {
      mask->tree().sparseFill(openvdb::CoordBBox(openvdb::Coord(run.x0, y, z),
                                                 openvdb::Coord(run.x1 - 1, y, z)),
                              true, true);
      if (label_grid) {
        auto lacc = label_grid->getAccessor();
        for (int32_t x = run.x0; x < run.x1; ++x) {
          lacc.setValue(openvdb::Coord(x, y, z), labels[first + (x - run.x0)]);
        }
      }
    });
    mask->setName(grid_name);
    SetVolumeMeta(*mask, set.dims(), DType::kUInt8, placement);
    grids.push_back(mask);
    if (label_grid) {
      label_grid->setName(grid_name + "_labels");
      SetVolumeMeta(*label_grid, set.dims(), DType::kFloat32, placement);
      grids.push_back(label_grid);
    }
  } catch (const openvdb::Exception& e) {
    return absl::InternalError(absl::StrCat(path, ": OpenVDB: ", e.what()));
  }
  return WriteGridsAtomically(path, grids);
}

}  // namespace sheetmesh
