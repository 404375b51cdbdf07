// Connected components of a VoxelSet under 6-, 18- or 26-connectivity, by union-find over
// runs (every voxel of a run shares its component).
#ifndef SHEETMESH_WORKER_PIPELINE_VOXEL_COMPONENTS_H_
#define SHEETMESH_WORKER_PIPELINE_VOXEL_COMPONENTS_H_

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// Face (6), face+edge (18) or face+edge+corner (26) neighbours.
enum class Connectivity { k6 = 6, k18 = 18, k26 = 26 };
absl::StatusOr<Connectivity> ParseConnectivity(int n);

struct Components {
  std::vector<uint32_t> run_label;  // component of each run of the set
  std::vector<uint64_t> sizes;      // voxels per component, largest first (label 0)

  uint32_t count() const { return static_cast<uint32_t>(sizes.size()); }
  // Component of each voxel, aligned with the set's voxel order.
  std::vector<uint32_t> VoxelLabels(const VoxelSet& set) const;
};

// Labels the components of `set`. Labels are ordered by size, largest first; ties by the
// first voxel's index, so the result is deterministic. kCancelled if `progress` asks.
absl::StatusOr<Components> LabelComponents(const VoxelSet& set, Connectivity connectivity,
                                           const Progress& progress = {});

struct RemovalResult {
  VoxelSet kept;
  uint64_t removed_components = 0;
  uint64_t removed_voxels = 0;
};

// Removes every component with fewer than `min_voxels` voxels (the volume criterion M of
// §2.2). min_voxels <= 1 keeps everything.
absl::StatusOr<RemovalResult> RemoveSmallComponents(const VoxelSet& set, uint64_t min_voxels,
                                                    Connectivity connectivity,
                                                    const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOXEL_COMPONENTS_H_
