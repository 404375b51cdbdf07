// NeighborTable: the six face neighbours of every voxel of a VoxelSet as voxel indices, so
// that breadth-first growth runs on plain arrays. 24 bytes per voxel.
#ifndef SHEETMESH_WORKER_PIPELINE_VOXEL_NEIGHBOR_TABLE_H_
#define SHEETMESH_WORKER_PIPELINE_VOXEL_NEIGHBOR_TABLE_H_

#include <array>
#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// Direction k of the table: 0 -x, 1 +x, 2 -y, 3 +y, 4 -z, 5 +z.
inline constexpr int kNumFaceNeighbors = 6;
inline constexpr uint32_t kNoNeighbor = UINT32_MAX;

class NeighborTable {
 public:
  // Builds the table of `set`. kResourceExhausted when the set has 2^32 - 1 voxels or more.
  static absl::StatusOr<NeighborTable> Build(const VoxelSet& set);

  // The neighbour of voxel `v` in direction `k`, or kNoNeighbor.
  uint32_t at(uint32_t v, int k) const { return table_[v][k]; }
  const std::array<uint32_t, 6>& of(uint32_t v) const { return table_[v]; }
  size_t size() const { return table_.size(); }

 private:
  std::vector<std::array<uint32_t, 6>> table_;
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOXEL_NEIGHBOR_TABLE_H_
