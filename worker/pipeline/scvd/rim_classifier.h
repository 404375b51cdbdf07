// RimClassifier: whether a sheet voxel lies on the sheet's rim (its outer edge or the edge of a
// hole) rather than on its faces: some step along the sheet — among the 26 neighbour
// directions, those nearly perpendicular to the local normal — leaves the sheet.
#ifndef SHEETMESH_WORKER_PIPELINE_SCVD_RIM_CLASSIFIER_H_
#define SHEETMESH_WORKER_PIPELINE_SCVD_RIM_CLASSIFIER_H_

#include <vector>

#include "common/types.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// Thread-compatible; holds a reference to `set`, which must outlive it.
class RimClassifier {
 public:
  // `max_cos`: a step d counts as along the sheet when |d . n| < max_cos |d|.
  RimClassifier(const VoxelSet& set, double max_cos);

  // True when voxel (x, y, z) of the set is on the rim for the unit normal `n`.
  bool IsRim(int32_t x, int32_t y, int32_t z, const Vec3& n) const;

 private:
  const VoxelSet& set_;
  double max_cos_;
  std::vector<Vec3> dirs_;
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SCVD_RIM_CLASSIFIER_H_
