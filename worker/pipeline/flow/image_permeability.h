// A reference for the mesh's permeability from the image itself (beyond the paper), so that
// a user sees how much meshing changed the answer. Each voxel is a cell of the grid: a
// sheet voxel of thickness τ (voxels; held to twice the sheets' median, as where sheets
// cross it is the crossing's length) has the permeability (τ h)²/12, so that a sheet τ
// voxels thick carries the cubic law's a³/12 with a = τ h; every other voxel has the rock's
// k_m. Darcy flow is solved on the grid by finite volumes (two-point fluxes, harmonic
// means between cells) as three permeameters: along each axis d the pressure −x_d on the
// two faces across d and no flow through the other four (held linear there as in the
// mesh's solve, a sheet voxel touching them would carry the imposed gradient across its
// thickness), the column d of the tensor from the mean fluxes. Along the axes its diagonal
// is the mesh's to compare with.
#ifndef SHEETMESH_WORKER_PIPELINE_FLOW_IMAGE_PERMEABILITY_H_
#define SHEETMESH_WORKER_PIPELINE_FLOW_IMAGE_PERMEABILITY_H_

#include <array>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <span>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "common/types.h"
#include "worker/pipeline/flow/permeability.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// The largest grid the pipeline solves the reference on (one unknown per voxel: a million
// cells take about 15 s on 2 cores, beside a volume mesh of a few seconds).
inline constexpr uint64_t kImageReferenceCells = uint64_t{1} << 20;

struct ImagePermeability {
  Tensor3 tensor{};                          // m²
  std::array<double, 3> principal{};         // largest first
  std::array<Vec3, 3> principal_directions;  // unit vectors, in that order
  // Per axis: the mesh's permeameter over the image's (set by CompareToImage).
  std::array<double, 3> mesh_to_image{};
  std::array<int, 3> iterations{};
  double residual = 0;
  uint64_t cells = 0;
  double seconds = 0;

  nlohmann::json Fields() const;
};

// Solves the grid of `dims` with `sheet` (its voxels' thickness τ in `thickness`, aligned
// with the set's voxel order) and voxels of `spacing_m` metres per axis. kInvalidArgument
// for a permeability out of range (as SolvePermeability) or a thickness list of another
// length; kResourceExhausted beyond `max_cells` cells; kInternal when the solver does not
// converge; kCancelled if asked.
absl::StatusOr<ImagePermeability> SolveImagePermeability(
    const VoxelSet& sheet, std::span<const uint16_t> thickness, const Vec3& spacing_m,
    const FlowOptions& options, uint64_t max_cells, const Progress& progress = {});

// Sets image->mesh_to_image from the mesh's permeameters and the image's.
void CompareToImage(const PermeabilityResult& mesh, ImagePermeability* image);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_FLOW_IMAGE_PERMEABILITY_H_
