// NeighborTable: the six face neighbours of every voxel of a VoxelSet as voxel indices, so
// that breadth-first growth runs on plain arrays. 17 bytes per voxel: the four across rows
// as indices, the two along its row (the voxels before and after it in index order) as two
// bits.
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
  uint32_t at(uint32_t v, int k) const {
    if (k >= 2) return across_[v][k - 2];
    return (along_[v] >> k) & 1 ? (k == 0 ? v - 1 : v + 1) : kNoNeighbor;
  }
  std::array<uint32_t, 6> of(uint32_t v) const {
    const std::array<uint32_t, 4>& a = across_[v];
    return {at(v, 0), at(v, 1), a[0], a[1], a[2], a[3]};
  }
  size_t size() const { return across_.size(); }

 private:
  std::vector<std::array<uint32_t, 4>> across_;  // -y, +y, -z, +z
  std::vector<uint8_t> along_;                   // bit 0: a -x neighbour, bit 1: a +x one
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOXEL_NEIGHBOR_TABLE_H_
