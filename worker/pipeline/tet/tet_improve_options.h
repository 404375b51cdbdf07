// The improvement pass's options and report (tet_improve.h runs the pass; its helpers, the
// flips, the insertion and the smoothing, take the options from here).
#ifndef SHEETMESH_WORKER_PIPELINE_TET_TET_IMPROVE_OPTIONS_H_
#define SHEETMESH_WORKER_PIPELINE_TET_TET_IMPROVE_OPTIONS_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>

namespace sheetmesh {

struct TetImproveOptions {
  int passes = 4;  // rounds of flips then smoothing; 0 switches the improvement off
  // Tetrahedra whose smallest dihedral angle is below this are offered to the flips; the
  // smoothing moves every free vertex whose star holds one. Higher costs more time and
  // lifts the mean further.
  double target_degrees = 50.0;
  // A tetrahedron still below this after the flips gets a new vertex beside it, kept where
  // that raises the worst tetrahedron of the cavity. This mends slivers whose vertices all
  // lie on sheets, which neither flips nor smoothing can, and raises the mean most of all
  // the operations (DPM: mean 44.4° at 20, 48.4° at 50, for 32% more tetrahedra and 4×
  // the time; bench/RESULTS.md). Lower is faster with fewer tetrahedra: at 40 (and 25
  // after the first pass) with the lattice graded at 2, the volume mesh sweep's median fell
  // from 21 to 13 tetrahedra per sheet triangle and the stage from 29x to 18x TetGen's
  // time, every run that reached 10 degrees still there, the median mean dihedral 47.9
  // degrees against 50.9 (bench/RESULTS.md, issue 65).
  double insert_below_degrees = 40.0;
  // After the first pass, only tetrahedra below this (or insert_below_degrees, if lower)
  // get a new vertex. Most later tries fail: on the 192³ phantom 1 in 77 between 40° and 50°
  // in the second pass, against 1 in 28 in the first; stopping them there takes a quarter off
  // the improvement's time for 0.06°–0.25° of mean (bench/RESULTS.md); 25 with the
  // defaults above.
  double insert_again_below_degrees = 25.0;
  // Smoothing first raises the worst tetrahedron of a vertex's star, then moves the vertex
  // to raise the star's mean shape (towards the volume-weighted mean of the circumcentres,
  // as in optimal Delaunay smoothing, and up the mean's gradient; see radius_weight). A
  // move for the mean may lower the star's worst tetrahedron, but never below this angle
  // or below where it already is. Lower gives the mean more room (radius aspect: DPM 0.823
  // at 30°, 0.832 at 20°; bench/RESULTS.md).
  double smoothing_floor_degrees = 20.0;
  // The shape whose mean the smoothing raises: (1 - w) · smallest dihedral angle +
  // w · 70.53° · radius aspect (both 70.53° for a regular tetrahedron). The dihedral angle
  // barely sees needles and wedges (a short edge, two close vertices), which the radius
  // aspect does; 0 raises the dihedral mean alone, 1 the radius aspect alone.
  double radius_weight = 0.5;
  // A tetrahedron below this that no point off the sheets lifts above it (its corners held
  // by the sheets around it: a sheet vertex just off another sheet's face, a flat gap
  // framed by sheet edges) may get its new vertex on a sheet face or sheet edge next to
  // it, which splits that face in three or the faces on that edge in two. The sheet faces
  // still tile every input triangle; only these few triangles become more than one face.
  // 0 keeps every sheet face as it came from TetGen. Only tetrahedra below
  // insert_below_degrees get a new vertex at all, so the lower of the two applies.
  double split_sheets_below_degrees = 15.0;
  // A tetrahedron below split_sheets_below_degrees whose corners are the sheets' own
  // vertices (a flat gap framed by sheet edges, four sheet vertices nearly on one circle)
  // is out of reach of every vertex off the sheets. Then the sheet vertices of its star
  // may move by at most this far from where the PLC put them (in units of the smallest
  // voxel edge; half as far where sheets meet), to raise the worst tetrahedron and nothing
  // else; vertices on the box stay. The sheet's faces move with them: the similarity of
  // the volume mesh's sheets counts the cost. 0 keeps every PLC vertex where it is.
  double sheet_move_voxels = 1.0;
  // The angle the mesh is meant to reach (tet.min_dihedral; the caller sets it). After the
  // passes, a PLC sheet vertex moved by sheet_move_voxels goes back towards where it began
  // as far as its star then stays at the mesh's minimum (or at this, where the minimum is
  // under it): the sheets change only where the angles need it.
  double aim_degrees = 10.0;
  // A budget: no flip or insertion that could take the mesh past this many tetrahedra
  // (0: none); at the budget, flips that add none (3-2, 4-4) still run. The caller sets it from
  // VolumeMeshOptions::max_tetrahedra.
  uint64_t max_tetrahedra = 0;
};

struct TetImproveReport {
  int passes = 0;                        // rounds run (stops early when a round changes nothing)
  uint64_t edge_removals = 0;            // edges removed (3-2, 4-4, 5-6, ... flips)
  uint64_t face_removals = 0;            // 2-3 flips
  uint64_t smoothing_moves = 0;          // vertex moves accepted
  uint64_t inserted_vertices = 0;        // new vertices (off slivers, or on sheets next to them)
  uint64_t sheet_face_splits = 0;        // of those, on a sheet face (splitting it in three)
  uint64_t sheet_edge_splits = 0;        // of those, on a sheet edge (splitting its faces in two)
  uint64_t box_face_splits = 0;          // new vertices on a box face (splitting it in three)
  uint64_t contracted_edges = 0;         // slivers' free corners merged into another corner
  uint64_t contracted_sheet_edges = 0;   // added sheet vertices merged along their sheet
  uint32_t moved_sheet_vertices = 0;     // PLC sheet vertices moved (sheet_move_voxels)
  double max_sheet_move = 0;             // the farthest of them moved, in the mesh's units
  uint32_t returned_sheet_vertices = 0;  // moved, then taken back all the way (not counted above)
  uint64_t over_budget = 0;       // insertions not tried for TetImproveOptions::max_tetrahedra
  uint64_t retries_skipped = 0;   // flips and moves not tried again: failed, nothing changed
  uint32_t movable_vertices = 0;  // vertices that may move (sliding ones included)
  uint32_t sliding_vertices = 0;  // sheet vertices TetGen added, free within their sheet
                                  // triangle or along their sheet edge
  double min_dihedral_before = 0, mean_dihedral_before = 0;  // degrees
  double min_dihedral_after = 0, mean_dihedral_after = 0;
  double seconds = 0;
  bool time_limited = false;  // stopped at tet.time_limit_seconds: its mesh as it was then

  // The figures by name, for the report.
  nlohmann::json Fields() const;
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_TET_IMPROVE_OPTIONS_H_
