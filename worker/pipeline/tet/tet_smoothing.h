// Smoothing for the improvement of a tetrahedral mesh: moves one vertex, within the moves
// its VertexFreedom allows, first to raise the smallest dihedral angle of its star, then
// to raise the star's mean shape (towards the volume-weighted mean of the circumcentres,
// as in optimal Delaunay smoothing, and up the mean's gradient) without lowering its worst
// below a floor. Internal to the improvement.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_TET_SMOOTHING_H_
#define SHEETMESH_WORKER_PIPELINE_TET_TET_SMOOTHING_H_

#include <cstdint>
#include <functional>
#include <vector>

#include "absl/status/status.h"
#include "common/progress.h"
#include "worker/pipeline/tet/tet_mesh_editor.h"
#include "worker/pipeline/tet/vertex_freedom.h"

namespace sheetmesh {

struct SmoothingOptions {
  double floor_degrees = 20;   // TetImproveOptions::smoothing_floor_degrees
  double radius_weight = 0.5;  // TetImproveOptions::radius_weight
};

// What the smoothing's second stage raises the star's sum of: the smallest dihedral angle
// q of tetrahedron t blended with its radius aspect, (1 - w) q + w 70.53° radius aspect.
double BlendedShape(const TetMeshEditor& ed, const Tet& t, double q, double radius_weight);

// Moves vertex v where its star is better; true when it moved (its star's qualities are
// measured again then). Nothing inverts.
bool SmoothVertex(TetMeshEditor& ed, const VertexFreedom& fr, uint32_t v,
                  const SmoothingOptions& options);

// One sweep of smoothing over `todo` (ids of vertices that may move, increasing) on all
// cores. The sweep goes in rounds: a round takes, in id order, the waiting vertices that
// share no tetrahedron with one taken before it (so no move sees another's: each looks at
// its own star only), and the others wait for the next round. As a round forms, `wants(v)` says
// whether v still needs a move (a neighbour's move may have lifted its star). After a round, in id
// order, each moved vertex's star is measured again and `done(v, moved)` is called for every vertex
// of the round. So the result depends on neither the number of threads nor their timing. Returns
// kCancelled if `progress` asks (between rounds; the mesh stays valid).
absl::Status SmoothVertices(TetMeshEditor& ed, const VertexFreedom& fr, std::vector<uint32_t> todo,
                            const SmoothingOptions& options,
                            const std::function<bool(uint32_t)>& wants,
                            const std::function<void(uint32_t, bool)>& done,
                            const Progress& progress);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_TET_SMOOTHING_H_
