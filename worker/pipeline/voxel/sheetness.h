// Sheets found on grey levels (beyond the paper): a fracture thinner than a voxel shows as
// voxels a little darker than the rock, which no global threshold separates from the noise.
// Across a thin dark sheet the grey levels curve up on both sides, along it they stay flat:
// of the Hessian's eigenvalues one is large and positive, two are small. The sheetness of
// a voxel is the largest, over a few scales, of that eigenvalue less the next one's
// magnitude (scale-normalised); voxels above a high threshold seed the sheets, which grow
// through voxels above a low one (hysteresis), so that a faint stretch of a sheet stays
// joined to its clear parts. The thresholds are in units of the sheetness's own noise over
// the volume, so that they hold at any contrast and noise.
#ifndef SHEETMESH_WORKER_PIPELINE_VOXEL_SHEETNESS_H_
#define SHEETMESH_WORKER_PIPELINE_VOXEL_SHEETNESS_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/voxel/grey_volume.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

struct SheetnessOptions {
  std::vector<double> scales = {0.75, 1.5, 3.0};  // Gaussian σ, voxels
  double high = 6.0;  // seeds: sheetness above this many noise units (each scale's median
                      // response)
  double low = 3.0;   // grown through voxels above this many
  // Work by slabs of about this many float voxels (the halo of the largest scale included;
  // a slab's core at least twice the halo thick), and measure the noise units on slices
  // spread through the volume holding about this many voxels (all of a smaller volume).
  int64_t slab_voxels = int64_t{96} << 20;
  int64_t noise_sample_voxels = int64_t{4} << 20;
};

struct SheetnessStats {
  std::vector<double> noise;  // each scale's median positive response (its noise unit)
  int64_t noise_slices = 0;   // measured on this many slices spread through the volume
  uint64_t slabs = 0;         // slabs worked
  uint64_t seeds = 0;         // voxels above `high`
  uint64_t detected = 0;      // voxels of the sheets after growing
  double seconds = 0;
  nlohmann::json Fields() const;
};

// The sheet voxels of `grey` (dark sheets in bright rock). The sheetness of a voxel is the
// largest over the scales of s² (λ3 − |λ2|) / (that scale's noise unit), where λ3 > 0 is
// the Hessian's eigenvalue of largest magnitude (else 0) of the grey levels smoothed at s,
// and only where they rise on both sides along its eigenvector as that curvature says (a
// valley's floor, not the dark side of a step). Worked slab by slab (floats for one slab
// and its halo at a time; the voxels found kept as runs), so that memory beyond the volume
// itself stays small at any size. kInvalidArgument for no scale, a
// scale outside (0, 16], or low above high; kCancelled if asked.
absl::StatusOr<VoxelSet> DetectSheets(const GreyVolume& grey, const SheetnessOptions& options,
                                      SheetnessStats* stats, const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOXEL_SHEETNESS_H_
