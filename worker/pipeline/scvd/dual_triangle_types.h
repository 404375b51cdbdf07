// What the dual triangulation (dual_triangles.h) is asked and what it gives: its options, its
// counts and its triangles. Apart so that its internal parts (dual_triangles_parts.h) need
// only these, not the triangulation.
#ifndef SHEETMESH_WORKER_PIPELINE_SCVD_DUAL_TRIANGLE_TYPES_H_
#define SHEETMESH_WORKER_PIPELINE_SCVD_DUAL_TRIANGLE_TYPES_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <vector>

#include "common/types.h"
#include "worker/pipeline/mesh/triangle_mesh.h"

namespace sheetmesh {

struct DualTriangleOptions {
  double fold_angle_degrees = 50.0;  // a candidate meeting a kept face at a smaller dihedral
                                     // angle along a shared edge folds onto it: rejected
  bool reject_intersections = true;  // reject candidates that cut through kept faces
  // Beyond the paper: the dual mesh stops at the outermost generators, leaving a band about
  // half a cell wide uncovered along every rim (ALGORITHM, "where the paper loses
  // fidelity"). With `rim`, each boundary cell gets a vertex at the centroid of its rim
  // voxels and a strip of triangles joins the mesh boundary to them.
  bool rim = true;
  // Beyond the paper: triangles rejected by the selection leave cracks — narrow notches in
  // the mesh boundary. A notch whose opening angle at a boundary vertex is below
  // crack_angle_degrees, whose closing edge is short and whose ear triangle lies on sheet
  // voxels is closed by that triangle; real holes (over empty space) stay open.
  bool close_cracks = true;
  double crack_angle_degrees = 60.0;
  // The longest closing edge of a crack, voxels; 0: 1.5 times the mesh's mean edge. A brick
  // gives one that does not depend on its mesh (bricked_surface.h).
  double crack_max_edge_voxels = 0.0;
  // For a brick of a larger image: the global position of the set's voxel (0, 0, 0), in
  // which frame the positions given are and the rim vertices come, so every brick computes
  // them as the whole image would, to the last bit; and the image's size, to which rim
  // vertices are kept (empty: the set's box).
  Index3 origin;
  Dims image;
  double rim_normal_cos = 0.4;   // a step d along the sheet has |d . n| / |d| below this
                                 // (n: the vertex normal); a voxel from which such a step
                                 // leaves the sheet is a rim voxel
  double rim_push_voxels = 0.0;  // rim vertices this far out past the outermost voxels'
                                 // centres (0.5: at the voxels' edge; off by default: the
                                 // volume mesh's smallest angles suffer, RESULTS)
};

struct DualTriangleStats {
  uint64_t blocks_three = 0;       // blocks with exactly three cells
  uint64_t blocks_amended = 0;     // blocks with four or more
  uint64_t blocks_unresolved = 0;  // of those, blocks whose cells form no polygon
  uint64_t candidates = 0;         // distinct candidate triangles
  uint64_t kept = 0;
  uint64_t rejected_degenerate = 0;
  uint64_t rejected_fold = 0;
  uint64_t rejected_intersection = 0;
  uint64_t rim_vertices = 0;  // rim vertices added
  uint64_t rim_faces = 0;     // of the kept faces, those on the rim strip
  uint64_t crack_faces = 0;   // of the kept faces, those closing cracks

  // The counts by name, for the report.
  nlohmann::json Fields() const;
};

struct DualTriangulation {
  // Vertex ids below the generator count G are generators; id G + k is rim vertex k.
  std::vector<Face> faces;
  std::vector<uint32_t> votes;       // blocks that voted for each face (0 for rim faces)
  std::vector<Vec3> rim_positions;   // rim vertex k's position
  std::vector<uint32_t> rim_cell;    // the cell (generator) whose rim it is
  std::vector<float> rim_thickness;  // mean τ of its rim voxels
  DualTriangleStats stats;
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SCVD_DUAL_TRIANGLE_TYPES_H_
