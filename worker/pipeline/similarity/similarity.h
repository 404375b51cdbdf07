// Shape similarity (paper §2.3.2, formula 5) of a mesh model against the image, with the
// Dice coefficient and the symmetric Hausdorff distance that other tools report, and the
// grid-model baseline of Table 2.
#ifndef SHEETMESH_WORKER_PIPELINE_SIMILARITY_SIMILARITY_H_
#define SHEETMESH_WORKER_PIPELINE_SIMILARITY_SIMILARITY_H_

#include <cstdint>

#include <nlohmann/json_fwd.hpp>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

struct SimilarityScore {
  uint64_t c_in = 0;      // model voxels that are image voxels
  uint64_t c_out = 0;     // model voxels that are not
  uint64_t c_image = 0;   // image voxels
  uint64_t c_model = 0;   // model voxels (c_in + c_out)
  double similarity = 0;  // (c_in - c_out) / c_image, in (-inf, 1]
  double dice = 0;        // 2 c_in / (c_model + c_image)
  double hausdorff = -1;  // symmetric, voxels; -1 when not computed

  // similarity, c_in, c_out, c_image, dice and, when computed, hausdorff_voxels.
  nlohmann::json Fields() const;
};

// Formula 5 and Dice of `model` against `image`. REQUIRES: equal dims; image not empty.
SimilarityScore ScoreModel(const VoxelSet& model, const VoxelSet& image);

// Symmetric Hausdorff distance in voxels between two sets: the largest distance from a
// voxel of one to the nearest voxel of the other. Infinity if exactly one is empty, 0 if
// both are. kCancelled if asked.
absl::StatusOr<double> HausdorffDistance(const VoxelSet& a, const VoxelSet& b,
                                         const Progress& progress = {});

// The grid model of Table 2: keep every k-th voxel of `image` on each axis and blow each
// kept voxel back up to a k x k x k block (clipped to the box). k = 1 gives the image.
// REQUIRES: k >= 1.
VoxelSet GridModel(const VoxelSet& image, int k);
// Cells of the coarse grid: ceil(nx/k) ceil(ny/k) ceil(nz/k) (Table 2's "grid quantity").
uint64_t GridQuantity(const Dims& dims, int k);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SIMILARITY_SIMILARITY_H_
