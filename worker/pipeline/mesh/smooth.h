// Smoothing a sheet's mid-surface where it is thicker than its triangles are wide
// (beyond the paper; ALGORITHM §4, thick sheets). Column middles of a thick sheet with rough
// walls wander by half the walls' roughness; triangles smaller than the thickness follow
// that wander, and their normals, along which the per-face prisms of formula 5 stand, tilt
// by tens of degrees — a prism 40 voxels tall tilted 30° misses much of the sheet. Taubin's
// λ|μ smoothing (no shrinking) takes the wander out where the thickness exceeds the edge
// length and leaves thin sheets as they are.
#ifndef SHEETMESH_WORKER_PIPELINE_MESH_SMOOTH_H_
#define SHEETMESH_WORKER_PIPELINE_MESH_SMOOTH_H_

#include <span>
#include <vector>

#include "worker/pipeline/mesh/triangle_mesh.h"

namespace sheetmesh {

struct SmoothOptions {
  int iterations = 30;  // λ|μ pairs
  double lambda = 0.5;  // the shrinking step
  double mu = -0.53;    // the inflating step
};

// The weight of each vertex: 0 where its thickness is at most its mean edge length, rising
// to 1 where it is twice that.
std::vector<double> ThicknessSmoothingWeights(const TriangleMesh& mesh,
                                              std::span<const float> vertex_thickness_voxels);

// Moves the vertices of `mesh` by `weight`-scaled λ|μ steps towards the mean of their
// neighbours. Vertices on a boundary or a non-manifold edge (rims, crossings) stay where they
// are; returns how many vertices moved.
size_t SmoothVertices(TriangleMesh* mesh, std::span<const double> weight,
                      const SmoothOptions& options = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_MESH_SMOOTH_H_
