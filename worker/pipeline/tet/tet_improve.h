// Improvement of TetGen's output (ALGORITHM §10–11). TetGen's refinement bounds the
// radius–edge ratio, which does not see slivers (four nearly coplanar vertices, most often
// all on a sheet), and leaves a mean smallest dihedral angle near 40°. This pass raises the
// quality without touching the sheets, in rounds of:
//  - flips that never remove a face on a facet: edge removal (the optimal triangulation of
//    the ring around an edge: 3-2, 4-4, 5-6, ... flips) and 2-3 face removal, first for the
//    worst tetrahedron they touch, then for the mean;
//  - a new vertex off a sliver that the flips cannot mend, inserted into a star-shaped
//    cavity that never crosses a facet; or, for the few slivers whose corners the sheets
//    pin (split_sheets_below_degrees), a new vertex on a sheet face or sheet edge beside
//    it, splitting that face in three or the faces on that edge in two, each piece keeping
//    its input triangle, piece and thickness;
//  - smoothing of the vertices: box vertices slide within their face or edge, so the
//    domain is unchanged; the vertices TetGen added on a sheet slide within the sheet
//    triangle or along the sheet edge they lie on, so the sheets are unchanged too (their
//    faces still tile every input triangle); the PLC's own vertices never move.
// A flip or an insertion is kept only if it raises the worst tetrahedron it touches (or,
// for the mean, raises the mean without lowering that worst), and nothing ever inverts.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_TET_IMPROVE_H_
#define SHEETMESH_WORKER_PIPELINE_TET_TET_IMPROVE_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "common/progress.h"
#include "worker/pipeline/tet/tet_mesh.h"

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
  // the time; bench/RESULTS.md). Lower is faster with fewer tetrahedra.
  double insert_below_degrees = 50.0;
  // After the first pass, only tetrahedra below this (or insert_below_degrees, if lower)
  // get a new vertex. Most later tries fail: on the 192³ phantom 1 in 77 between 40° and 50°
  // in the second pass, against 1 in 28 in the first; stopping them there takes a quarter off
  // the improvement's time for 0.06°–0.25° of mean (bench/RESULTS.md).
  double insert_again_below_degrees = 40.0;
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
  // A budget: no flip or insertion that could take the mesh past this many tetrahedra
  // (0: none); at the budget, flips that add none (3-2, 4-4) still run. The caller sets it from
  // VolumeMeshOptions::max_tetrahedra.
  uint64_t max_tetrahedra = 0;
};

struct TetImproveReport {
  int passes = 0;                  // rounds run (stops early when a round changes nothing)
  uint64_t edge_removals = 0;      // edges removed (3-2, 4-4, 5-6, ... flips)
  uint64_t face_removals = 0;      // 2-3 flips
  uint64_t smoothing_moves = 0;    // vertex moves accepted
  uint64_t inserted_vertices = 0;  // new vertices (off slivers, or on sheets next to them)
  uint64_t sheet_face_splits = 0;  // of those, on a sheet face (splitting it in three)
  uint64_t sheet_edge_splits = 0;  // of those, on a sheet edge (splitting its faces in two)
  uint64_t over_budget = 0;        // insertions not tried for TetImproveOptions::max_tetrahedra
  uint64_t retries_skipped = 0;    // flips and moves not tried again: failed, nothing changed
  uint32_t movable_vertices = 0;   // vertices that may move (sliding ones included)
  uint32_t sliding_vertices = 0;   // sheet vertices TetGen added, free within their sheet
                                   // triangle or along their sheet edge
  double min_dihedral_before = 0, mean_dihedral_before = 0;  // degrees
  double min_dihedral_after = 0, mean_dihedral_after = 0;
  double seconds = 0;

  // The figures by name, for the report.
  nlohmann::json Fields() const;
};

// Improves `mesh` in place. Nodes [0, input_nodes) are the PLC's vertices and never move
// if they are on a sheet. The faces (the facets' triangles, box and sheets) stay faces,
// each of them within the facet it tiles, and vertices on the box faces stay on them, so the
// mesh keeps conforming to the PLC bounded by [box_lo, box_hi]. Tetrahedra must be
// positively oriented (TetVolume > 0). Returns kCancelled if `progress` asks, leaving a
// valid mesh.
absl::Status ImproveTetMesh(TetMesh* mesh, const Vec3& box_lo, const Vec3& box_hi,
                            uint32_t input_nodes, const TetImproveOptions& options,
                            TetImproveReport* report, const Progress& progress = {});

// The smallest dihedral angle of the tetrahedron (a, b, c, d) in degrees, or a negative
// number when it is inverted or flat (TetVolume <= 0).
double MinDihedralDegrees(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_TET_IMPROVE_H_
