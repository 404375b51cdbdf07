// Attributes of sheet triangles measured on the image: thickness (paper §2.3.2: the mean
// τ of the sheet voxels a triangle passes through) and the object each triangle belongs to.
#ifndef SHEETMESH_WORKER_PIPELINE_SIMILARITY_FACE_ATTRIBUTES_H_
#define SHEETMESH_WORKER_PIPELINE_SIMILARITY_FACE_ATTRIBUTES_H_

#include <cstdint>
#include <span>
#include <vector>

#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// How a thickness is read off the per-voxel τ.
enum class ThicknessMeasure {
  kAxisRuns,  // τ as it is: the shortest axis run (the paper)
  kNormal,    // τ times max_k |n_k| of the face normal n: a slab of thickness T with normal
              // n has axis runs of T / |n_k|, the shortest along the axis nearest n, so this
              // is T exactly for plane slabs at any tilt (beyond the paper)
};

// Per face: the mean τ of the voxels of `set` whose centre lies within half a voxel
// diagonal (√3/2) of the triangle (ALGORITHM §8), read with `measure`; 0 where it passes
// through none (a hole).
std::vector<float> FaceThickness(const TriangleMesh& mesh, const VoxelSet& set,
                                 std::span<const uint16_t> thickness,
                                 ThicknessMeasure measure = ThicknessMeasure::kAxisRuns);

// max_k |n_k| of a unit normal: the factor that turns an axis-run thickness into the
// thickness along n.
double AxisRunToNormalFactor(const Vec3& unit_normal);

// Per face: the most common label among its three vertices' labels (ties: the lowest).
std::vector<int32_t> FaceLabels(const TriangleMesh& mesh, std::span<const int32_t> vertex_label);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SIMILARITY_FACE_ATTRIBUTES_H_
