// Per-voxel thickness (ALGORITHM §1, paper §2.3.2): for each axis the length of the maximal
// run of sheet voxels through the voxel; the smallest of the three.
#ifndef SHEETMESH_WORKER_PIPELINE_VOXEL_THICKNESS_H_
#define SHEETMESH_WORKER_PIPELINE_VOXEL_THICKNESS_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// τ per voxel of `set`, aligned with its voxel order, in voxels (runs longer than 65535
// saturate). Two linear sweeps per axis; memory: 4 bytes per voxel plus one slice of ints.
// kCancelled if `progress` asks.
absl::StatusOr<std::vector<uint16_t>> ComputeThickness(const VoxelSet& set,
                                                       const Progress& progress = {});

struct ThicknessStats {
  double mean = 0;  // t̄ of formula 3
  uint32_t min = 0;
  uint32_t max = 0;
  double median = 0;
  std::vector<uint64_t> histogram;  // histogram[t] = voxels with τ == t (t = 0 unused)

  // mean, median, min, max (not the histogram), for the report.
  nlohmann::json Fields() const;
};

// Summary of per-voxel thickness values. All zero for an empty input.
ThicknessStats SummarizeThickness(std::span<const uint16_t> thickness);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOXEL_THICKNESS_H_
