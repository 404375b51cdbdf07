#include "worker/pipeline/voxel/sheet_analysis.h"

#include "common/status_macros.h"

namespace sheetmesh {

absl::StatusOr<SheetAnalysis> AnalyzeSheet(VoxelSet set, const Progress& progress) {
  if (set.empty()) return absl::InvalidArgumentError("the sheet phase is empty");
  SheetAnalysis a;
  SM_ASSIGN_OR_RETURN(a.thickness, ComputeThickness(set, progress.Sub(0, 0.4)));
  a.thickness_stats = SummarizeThickness(a.thickness);
  SM_ASSIGN_OR_RETURN(a.neighbors, NeighborTable::Build(set));
  SM_RETURN_IF_ERROR(progress.Update(0.7));
  SM_ASSIGN_OR_RETURN(a.components, LabelComponents(set, Connectivity::k6, progress.Sub(0.7, 1.0)));
  a.set = std::move(set);
  return a;
}

}  // namespace sheetmesh
