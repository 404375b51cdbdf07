#include "worker/pipeline/voxel/labelled_voxels.h"

#include <algorithm>
#include <map>

namespace sheetmesh {

uint32_t LabelledVoxels::CountLabels() const {
  std::vector<int32_t> l(label);
  std::sort(l.begin(), l.end());
  return static_cast<uint32_t>(std::unique(l.begin(), l.end()) - l.begin());
}

void LabelledVoxels::RelabelBySize() {
  std::map<int32_t, uint64_t> count;
  for (int32_t l : label) ++count[l];
  std::vector<std::pair<int32_t, uint64_t>> order(count.begin(), count.end());
  std::stable_sort(order.begin(), order.end(),
                   [](const auto& a, const auto& b) { return a.second > b.second; });
  std::map<int32_t, int32_t> renum;
  for (size_t i = 0; i < order.size(); ++i) renum[order[i].first] = static_cast<int32_t>(i);
  for (int32_t& l : label) l = renum[l];
}

LabelledVoxels LabelByComponents(VoxelSet set, const Components& components) {
  LabelledVoxels out;
  const std::vector<uint32_t> l = components.VoxelLabels(set);
  out.label.assign(l.begin(), l.end());
  out.set = std::move(set);
  return out;
}

}  // namespace sheetmesh
