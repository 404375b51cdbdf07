// Binary morphology on VoxelSets: dilation, erosion, opening and closing (the refine step
// of §2.2.1), one structuring element step per unit of radius, row by row on runs.
#ifndef SHEETMESH_WORKER_PIPELINE_VOXEL_MORPHOLOGY_H_
#define SHEETMESH_WORKER_PIPELINE_VOXEL_MORPHOLOGY_H_

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/voxel/components.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// Each step grows by the neighbours of `connectivity` (6: a cross, as OpenVDB's NN_FACE;
// 26: a 3x3x3 box), so `radius_voxels` steps of 6-connectivity give an L1 ball.
// Dilation is clipped to the box. Erosion treats voxels outside the box as set, so a sheet
// that runs into the box wall does not erode there. radius 0 returns the input.
// kInvalidArgument for a negative radius; kCancelled if `progress` asks.
absl::StatusOr<VoxelSet> Dilate(const VoxelSet& set, int radius_voxels,
                                Connectivity connectivity = Connectivity::k6,
                                const Progress& progress = {});
absl::StatusOr<VoxelSet> Erode(const VoxelSet& set, int radius_voxels,
                               Connectivity connectivity = Connectivity::k6,
                               const Progress& progress = {});
// Erode then dilate: removes specks and spurs thinner than 2 * radius.
absl::StatusOr<VoxelSet> Open(const VoxelSet& set, int radius_voxels,
                              Connectivity connectivity = Connectivity::k6,
                              const Progress& progress = {});
// Dilate then erode: fills gaps and holes narrower than 2 * radius.
absl::StatusOr<VoxelSet> Close(const VoxelSet& set, int radius_voxels,
                               Connectivity connectivity = Connectivity::k6,
                               const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOXEL_MORPHOLOGY_H_
