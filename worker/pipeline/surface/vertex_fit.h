// Moving the vertices of a one-layer sheet mesh onto the sheet it stands for (beyond the
// paper): a local optimisation of formula 5 itself, after the decimation and the fit of
// face heights (wall_fit.h).
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_VERTEX_FIT_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_VERTEX_FIT_H_

#include <cstdint>

#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

struct VertexFitOptions {
  int passes = 3;  // sweeps over the vertices
  // Moves along the normal too (the mid-surface off the sheet's middle). Off by default:
  // over the volume mesh sweep they tilt faces into creases that cost the volume mesh its
  // angles (bench/RESULTS.md, issue 42).
  bool along_normal = false;
  double step = 0.5;            // voxels: a move is one or two steps
  double max_offset = 1.5;      // voxels a vertex may end from where it started
  double max_normal_turn = 30;  // degrees a face's normal may turn from where it started
  double min_angle = 20;        // degrees: no face's least angle falls below this (or below
                                // what it had, if less)
  int junction_rings = 1;       // vertices this many rings of faces from a junction stay
  double box_reach = 1.5;       // voxels: a rim this near a face of the box (the outermost
                                // voxels' outer faces, −0.5 and n − 0.5) may move onto it
};

struct VertexFitStats {
  uint64_t vertices_tried = 0;
  uint64_t moves = 0;         // accepted moves, over all passes
  int64_t voxels_gained = 0;  // formula 5's numerator C_in − C_out rose by this much
};

// Moves vertices of a sheet mesh where formula 5 of all the prisms together (face heights
// `mesh.face_thickness_voxels`) rises: each rim vertex in turn tries one or two steps across the
// rim (the outline of the outermost voxels; each rim edge's two ends together too) and, with
// `along_normal`, every vertex along its normal, and takes the move that gains
// most, as long as no face turns, folds or sharpens past the options' bounds. A rim within
// `box_reach` of a face of the box goes onto it unless that loses. Vertices on and beside
// junctions of sheets stay, a coordinate in a face of the box stays, and no vertex comes
// nearer than a voxel to a face of the box otherwise. `mesh.face_thickness_voxels` must be set.
VertexFitStats FitVertexPositions(TriangleMesh* mesh, const VoxelSet& set,
                                  const VertexFitOptions& options = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_VERTEX_FIT_H_
