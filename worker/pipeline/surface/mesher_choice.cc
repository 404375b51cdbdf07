#include "worker/pipeline/surface/mesher_choice.h"

#include <utility>

#include "common/status_macros.h"
#include "worker/pipeline/similarity/mesh_model.h"
#include "worker/pipeline/similarity/similarity.h"

namespace sheetmesh {

absl::StatusOr<RadiusSearchResult> BuildWithBothMeshers(
    const SheetAnalysis& sheet, PrismHeight height,
    const std::function<absl::StatusOr<RadiusSearchResult>(SurfaceMethod, const Progress&)>& build,
    const Progress& progress) {
  SM_ASSIGN_OR_RETURN(RadiusSearchResult scvd, build(SurfaceMethod::kScvd, progress.Sub(0, 0.5)));
  SM_ASSIGN_OR_RETURN(RadiusSearchResult mid, build(SurfaceMethod::kMid, progress.Sub(0.5, 1)));
  MesherChoiceStats c;
  c.margin = kMesherMargin;
  for (auto [built, score] : {std::pair{&scvd, &c.scvd_similarity}, {&mid, &c.mid_similarity}}) {
    if (built->surface.mesh.faces.empty()) continue;
    SM_ASSIGN_OR_RETURN(VoxelSet model,
                        VoxelizeMesh(built->surface.mesh, sheet.set.dims(), height));
    *score = ScoreModel(model, sheet.set).similarity;
  }
  c.kept_mid =
      !mid.surface.mesh.faces.empty() && c.mid_similarity >= c.scvd_similarity - kMesherMargin;
  RadiusSearchResult& kept = c.kept_mid ? mid : scvd;
  kept.surface.mesher_choice = c;
  return std::move(kept);
}

}  // namespace sheetmesh
