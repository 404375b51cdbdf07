// Decimation of a sheet mesh by edge collapses (quadric error, Garland & Heckbert 1997):
// where the sheet is flat its triangles merge freely, where it bends they stay, so a
// budget of triangles goes where the shape needs it. The rim is kept by planes across
// each boundary edge, and vertices on an edge of three or more faces (a junction of
// sheets) stay where they are.
#ifndef SHEETMESH_WORKER_PIPELINE_MESH_DECIMATE_H_
#define SHEETMESH_WORKER_PIPELINE_MESH_DECIMATE_H_

#include <cstdint>

#include "worker/pipeline/mesh/triangle_mesh.h"

namespace sheetmesh {

struct DecimateOptions {
  uint64_t triangles = 0;         // collapse until at most this many faces remain
  double boundary_weight = 4.0;   // weight of the planes across boundary edges
  double max_normal_turn = 45.0;  // degrees a face's normal may turn in one collapse
  double max_error = 1e300;       // stop once the cheapest collapse costs more (voxels²)
  // A vertex off rims and junctions may also go where its quadric is least (Garland &
  // Heckbert's optimal placement), not only to an end or the middle of the edge; a refused
  // collapse tries the edge's next option, and is tried again when a neighbouring collapse
  // moves its faces. The closed surfaces of bodies use it (their corners and creases lie
  // between the voxels'); sheets keep the plain rule their figures were measured with.
  bool optimal_placement = false;
  // Vertices lying in a face of the box [box_lo, box_hi] stay in it (a body closed by the
  // box's face keeps that face flat), and one on two faces stays on their edge.
  bool keep_box = false;
  Vec3 box_lo, box_hi;
};

struct DecimateStats {
  uint64_t faces_before = 0;
  uint64_t faces_after = 0;
  uint64_t collapses = 0;
  double largest_error = 0;  // the cost of the dearest collapse made
};

// Decimates `mesh` in place. Per-face arrays (face_piece, face_thickness_voxels) follow their
// faces; per-vertex thickness is dropped (the caller recomputes what it needs). A collapse
// that would change the mesh's topology (or take a piece's last faces), flip or fold a
// face, or move a vertex of an edge of three or more faces off its junction curve (or
// move one where curves meet or a curve reaches a rim) is not made, so the target may not
// be reached.
DecimateStats Decimate(TriangleMesh* mesh, const DecimateOptions& options);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_MESH_DECIMATE_H_
