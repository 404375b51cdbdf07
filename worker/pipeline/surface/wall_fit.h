// Fitting a one-layer sheet mesh to the walls of the sheet it stands for (beyond the paper):
// each face's thickness chosen for the best formula-5 score of all the prisms together
// rather than the mean τ of the voxels it passes through.
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_WALL_FIT_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_WALL_FIT_H_

#include <cstdint>
#include <span>
#include <vector>

#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// Per face: the height h of a prism on the triangle (as ALGORITHM §9 voxelises it) chosen
// to raise formula 5 of all the prisms together: coordinate descent, face after face for
// `passes` passes, each taking the height (up to `max_height[f]`) that gains most given
// the others — a voxel of `set` no other prism holds gains 1, any other voxel no prism
// holds costs 1. 0 where no height gains (the triangle spans a hole or is covered already).
std::vector<float> FitFaceThickness(const TriangleMesh& mesh, const VoxelSet& set,
                                    std::span<const float> max_height, int passes = 2);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_WALL_FIT_H_
