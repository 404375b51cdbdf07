#include "worker/pipeline/surface/error_density.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "worker/pipeline/similarity/mesh_model.h"
#include "worker/pipeline/similarity/similarity.h"

namespace sheetmesh {

std::vector<float> ErrorDensity(const SheetAnalysis& sheet, const Scvd& first,
                                const VoxelSet& model, double strength) {
  const uint32_t cells = first.num_generators();
  std::vector<uint64_t> missed(cells, 0), size(cells, 0);
  uint64_t all_missed = 0, all = 0;
  sheet.set.ForEachVoxel([&](uint64_t v, int32_t x, int32_t y, int32_t z) {
    const uint32_t c = first.cell[v];
    if (c == kNoCell) return;
    const bool miss = !model.Contains(x, y, z);
    missed[c] += miss;
    ++size[c];
    all_missed += miss;
    ++all;
  });
  std::vector<float> rho(sheet.set.size(), 1.0f);
  if (all_missed == 0) return rho;
  const double mean = double(all_missed) / double(all);
  for (size_t v = 0; v < rho.size(); ++v) {
    const uint32_t c = first.cell[v];
    if (c == kNoCell) continue;
    const double e = double(missed[c]) / double(size[c]);
    rho[v] = static_cast<float>(1 + strength * std::min(4.0, e / mean));
  }
  return rho;
}

absl::StatusOr<SurfaceResult> BuildErrorDrivenSurface(const SheetAnalysis& sheet,
                                                      const SurfaceOptions& options,
                                                      std::span<const int32_t> piece_of_voxel,
                                                      const Progress& progress) {
  SurfaceOptions plain = options;
  plain.error_density = 0;
  SM_ASSIGN_OR_RETURN(SurfaceResult first,
                      BuildSurface(sheet, plain, piece_of_voxel, progress.Sub(0, 0.45)));
  const Dims& dims = sheet.set.dims();
  SM_ASSIGN_OR_RETURN(VoxelSet model, VoxelizePrisms(first.mesh, dims));
  const double first_score = ScoreModel(model, sheet.set).similarity;
  const std::vector<float> rho = ErrorDensity(sheet, first.scvd, model, options.error_density);
  model = VoxelSet();
  SurfaceOptions weighted = plain;
  weighted.scvd.density = rho;
  SM_ASSIGN_OR_RETURN(SurfaceResult second,
                      BuildSurface(sheet, weighted, piece_of_voxel, progress.Sub(0.45, 0.9)));
  SM_ASSIGN_OR_RETURN(model, VoxelizePrisms(second.mesh, dims));
  const double second_score = ScoreModel(model, sheet.set).similarity;
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  ErrorDensityStats stats{first_score, second_score, second_score > first_score};
  SurfaceResult& kept = stats.kept_weighted ? second : first;
  kept.error_density = stats;
  kept.scvd_seconds = first.scvd_seconds + second.scvd_seconds;
  return std::move(kept);
}

absl::StatusOr<SurfaceResult> BuildRequestedSurface(const SheetAnalysis& sheet,
                                                    const SurfaceOptions& options,
                                                    std::span<const int32_t> piece_of_voxel,
                                                    const Progress& progress) {
  if (options.error_density > 0) {
    if (options.bricks.brick > 0) {
      return absl::InvalidArgumentError(absl::StrCat(
          "surface.bricks = ", options.bricks.brick, " cannot take surface.error_density = ",
          options.error_density, ": the error's density is scaled over the whole sheet"));
    }
    return BuildErrorDrivenSurface(sheet, options, piece_of_voxel, progress);
  }
  return BuildSurface(sheet, options, piece_of_voxel, progress);
}

}  // namespace sheetmesh
