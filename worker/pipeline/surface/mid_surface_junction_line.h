// A junction line of the mid-surface (mid_surface_junctions.h): where charts meet, straight,
// sampled into vertices every chart ending there shares.
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_JUNCTION_LINE_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_JUNCTION_LINE_H_

#include <cmath>
#include <cstdint>
#include <vector>

#include "common/types.h"

namespace sheetmesh {

// A straight junction where charts meet: the points p + t u, t in [t0, t1], sampled every
// `step` voxels (the ends are samples); sample k is vertex vertex_of[k] of the mesh once made
// (UINT32_MAX before).
struct JunctionLine {
  Vec3 point;
  Vec3 direction;  // unit
  double t0 = 0, t1 = 0, step = 1;
  double degrees = 0;                 // between the charts' planes there (the acute one)
  bool node0 = false, node1 = false;  // whether the end at t0 / t1 lies on another line
  std::vector<int32_t> charts;        // the charts that end on it
  std::vector<uint32_t> vertex_of;    // per sample
  std::vector<double> thickness;      // per chart in `charts`: its thickness at the line
  // Per chart: its piece and its plane at the line (the planes cross on it).
  std::vector<int32_t> pieces;
  std::vector<Vec3> plane_points, plane_normals;
  int samples() const { return static_cast<int>(std::floor((t1 - t0) / step + 1e-6)) + 1; }
  Vec3 At(int k) const { return point + direction * (t0 + k * step); }
  // The squared distance of p from the (unbounded) line.
  double Distance2(const Vec3& p) const {
    const Vec3 w = p - point;
    return Norm2(w - direction * Dot(w, direction));
  }
};

// How junctions are found and sampled (mid_surface_junctions.h).
struct JunctionOptions {
  double min_degrees = 4;     // planes closer to parallel meet in no junction (a near contact)
  uint64_t min_contact = 12;  // voxels of contact for a junction
  double sample_step = 1.0;   // voxels between the line's vertices
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_JUNCTION_LINE_H_
