// Error-driven sizing (ALGORITHM §3, formula 2 with a density; beyond the paper, which sets
// ρ = 1): a first surface at the asked r shows where one layer of prisms misses the sheet —
// where it bends, its aperture changes or sheets meet. Each SCVD cell's share of voxels no
// prism covers becomes the density ρ of its voxels, and a second SCVD with the same number
// of generators puts smaller cells there and larger ones where the sheet is planar with a
// constant aperture (formula 3 gives both the same generators per component). The better
// of the two surfaces by formula 5 is kept.
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_ERROR_DENSITY_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_ERROR_DENSITY_H_

#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "worker/pipeline/surface/surface_builder.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// ρ per voxel of `sheet`: 1 + strength · e_c / ē, with e_c the share of the voxels of the
// voxel's cell in `first.scvd` that `model` (the first surface's prisms) leaves out and ē
// that share over the whole sheet; at most 1 + 4 · strength. All 1 when nothing is missed.
std::vector<float> ErrorDensity(const SheetAnalysis& sheet, const Scvd& first,
                                const VoxelSet& model, double strength);

// BuildSurface twice as above (options.error_density > 0); the result carries which was
// kept in `error_density`.
absl::StatusOr<SurfaceResult> BuildErrorDrivenSurface(const SheetAnalysis& sheet,
                                                      const SurfaceOptions& options,
                                                      std::span<const int32_t> piece_of_voxel,
                                                      const Progress& progress);

// The surface `options` ask for: BuildErrorDrivenSurface when options.error_density > 0,
// else BuildSurface.
absl::StatusOr<SurfaceResult> BuildRequestedSurface(const SheetAnalysis& sheet,
                                                    const SurfaceOptions& options,
                                                    std::span<const int32_t> piece_of_voxel = {},
                                                    const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_ERROR_DENSITY_H_
