// LabelledVoxels: a voxel set whose voxels carry an object label (>= 0), aligned with the
// set's voxel order — the "3D image model" of Fig. 12(c).
#ifndef SHEETMESH_WORKER_PIPELINE_VOXEL_LABELLED_VOXELS_H_
#define SHEETMESH_WORKER_PIPELINE_VOXEL_LABELLED_VOXELS_H_

#include <cstdint>
#include <vector>

#include "worker/pipeline/voxel/components.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

struct LabelledVoxels {
  VoxelSet set;
  std::vector<int32_t> label;  // one per voxel of `set`

  // Distinct labels.
  uint32_t CountLabels() const;
  // Labels renumbered 0, 1, ... by voxel count, largest first (ties: the lower old label).
  void RelabelBySize();
  // The voxels whose label satisfies keep(label).
  template <class Keep>
  LabelledVoxels Select(Keep keep) const {
    std::vector<uint8_t> flags(label.size());
    LabelledVoxels out;
    for (size_t i = 0; i < label.size(); ++i) {
      flags[i] = keep(label[i]) ? 1 : 0;
      if (flags[i]) out.label.push_back(label[i]);
    }
    out.set = set.Filter(flags);
    return out;
  }
};

// The set with each voxel labelled by its component (6-connectivity), largest first.
LabelledVoxels LabelByComponents(VoxelSet set, const Components& components);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOXEL_LABELLED_VOXELS_H_
