#include "worker/pipeline/voxel/voxel_set_vdb.h"

#include <vector>

#include "worker/pipeline/volume/vdb_io.h"

namespace sheetmesh {

absl::Status WriteVoxelSetVdb(const std::string& path, const VoxelSet& set,
                              std::span<const int32_t> labels, const Placement& placement,
                              const std::string& grid_name) {
  // OpenVDB stays in the volume layer's one adapter (vdb_io.cc): this passes the runs.
  std::vector<SparseRun> runs;
  set.ForEachRun([&](int32_t y, int32_t z, const Run& run, uint64_t) {
    runs.push_back({run.x0, run.x1, y, z});
  });
  return WriteSparseVdb(path, set.dims(), runs, labels, placement, grid_name);
}

}  // namespace sheetmesh
