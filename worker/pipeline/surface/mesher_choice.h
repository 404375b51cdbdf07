// surface.mesher auto (beyond the paper): the SCVD's surface and the mid-surface both built
// and scored by formula 5; the mid-surface, whose junctions are at the rock's angles, is kept
// unless it scores clearly below the SCVD's.
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_MESHER_CHOICE_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_MESHER_CHOICE_H_

#include <functional>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/similarity/face_attributes.h"
#include "worker/pipeline/surface/radius_search.h"
#include "worker/pipeline/voxel/sheet_analysis.h"

namespace sheetmesh {

// The mid-surface is kept down to this far below the SCVD's similarity.
inline constexpr double kMesherMargin = 0.01;

// Builds the surface of each mesher with `build` (kScvd first, then kMid; each with its own
// pieces and, where asked, its own search of r), scores both against sheet.set with prisms of
// `height`, and returns the one kept with surface.mesher_choice set. Errors of `build` and
// of the scoring pass through.
absl::StatusOr<RadiusSearchResult> BuildWithBothMeshers(
    const SheetAnalysis& sheet, PrismHeight height,
    const std::function<absl::StatusOr<RadiusSearchResult>(SurfaceMethod, const Progress&)>& build,
    const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_MESHER_CHOICE_H_
