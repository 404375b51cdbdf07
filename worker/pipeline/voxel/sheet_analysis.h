// SheetAnalysis: what every meshing step needs to know about a sheet set — per-voxel
// thickness τ and its mean t̄, face neighbours, 6-connected components — computed once.
#ifndef SHEETMESH_WORKER_PIPELINE_VOXEL_SHEET_ANALYSIS_H_
#define SHEETMESH_WORKER_PIPELINE_VOXEL_SHEET_ANALYSIS_H_

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/voxel/components.h"
#include "worker/pipeline/voxel/neighbor_table.h"
#include "worker/pipeline/voxel/thickness.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

struct SheetAnalysis {
  VoxelSet set;
  std::vector<uint16_t> thickness;  // τ per voxel
  ThicknessStats thickness_stats;   // mean = t̄
  NeighborTable neighbors;
  Components components;  // 6-connectivity: the cells' growth cannot cross them
};

// Analyses `set`. kInvalidArgument for an empty set; kCancelled if asked.
absl::StatusOr<SheetAnalysis> AnalyzeSheet(VoxelSet set, const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOXEL_SHEET_ANALYSIS_H_
