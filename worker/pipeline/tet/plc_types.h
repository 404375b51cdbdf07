// The piecewise-linear complex's data (plc.h builds it): its facets, what building it
// changed, the options, and a clash of two sheet triangles. Apart from plc.h so that the
// PLC's internal parts (plc_parts.h) need only the types, not the builder.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_PLC_TYPES_H_
#define SHEETMESH_WORKER_PIPELINE_TET_PLC_TYPES_H_

#include <array>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "common/types.h"

namespace sheetmesh {

// A facet: one or more polygons (a polygon of 2 vertices is an embedded segment, of 1 an
// embedded point) with a boundary marker.
struct PlcFacet {
  std::vector<std::vector<uint32_t>> polygons;
  int32_t marker = 0;
};

inline constexpr int32_t kBoundaryMarker = 1;     // the box faces
inline constexpr int32_t kFirstSheetMarker = 10;  // sheet triangle t has marker 10 + t
// The seeded points (box points, lattice) sit on regular lattices, in many sets of four or
// five on one sphere or plane with the sheets' traces on the box. TetGen 1.5 resolves most
// such ties but not all: DPM's sheet at y = 49.5 met the box's seeds so that every TetGen
// run aborted while recovering segments (`run --r=7`: "terminate called after throwing an
// instance of 'int'"). Each seed moves by a fixed pseudo-random offset of at most half
// this (voxels) per free coordinate; a box point stays in its face or on its edge.
inline constexpr double kSeedJitterVoxels = 1e-4;

// What building the PLC changed, for the report.
struct PlcStats {
  uint32_t snapped_vertices = 0;        // moved onto a box face
  uint32_t snap_held_vertices = 0;      // within snap_clear_voxels of a box face, left off
                                        // it since snapping them made a clash
  uint32_t merged_vertices = 0;         // merged into a near-duplicate
  uint32_t dropped_triangles = 0;       // degenerate after snapping, or lying in a box face
  uint32_t repaired_triangles = 0;      // removed because they clashed after untangling
                                        // (PlcOptions::repair)
  double repaired_area_voxels = 0;      // their area, voxels^2
  uint32_t clashing_pairs = 0;          // sheet triangle pairs that cut through each other
                                        // before untangling
  uint32_t untangle_moves = 0;          // vertices moved to untangle them (PlcOptions::
                                        // untangle_voxels)
  uint32_t untangle_flips = 0;          // edges flipped to untangle them
  uint32_t untangle_splits = 0;         // crossing pairs split to meet in an edge
  uint32_t untangle_thin_splits = 0;    // of those, split as a last resort with thin pieces
  uint32_t untangle_patches = 0;        // patches re-triangulated to untangle them
  double untangle_max_move = 0;         // the largest of those moves, voxels
  uint32_t flipped_edges = 0;           // sheet edges flipped for better triangles
  uint32_t dropped_caps = 0;            // flat rim triangles dropped
  uint32_t dropped_overlaps = 0;        // rim triangles dropped for lying on another sheet
  uint32_t closed_slits = 0;            // slits framed by three rim edges closed by
                                        // splitting a face (PlcOptions::cap_degrees)
  uint32_t closed_caps = 0;             // sheet triangles with a corner over cap_degrees left
                                        // by the mends, closed onto their long edge (CloseCaps)
  uint32_t straightened_junctions = 0;  // junction vertices moved onto the line between
                                        // their neighbours (PlcOptions::junction_voxels)
  uint32_t opened_dihedral_wedges = 0;  // sheet vertices turned about an edge to open a
                                        // narrow wedge between two faces there
  uint32_t opened_wedges = 0;           // sheet vertices moved off a sheet face's plane
                                        // to open a narrow wedge (PlcOptions::wedge_degrees)
  uint32_t split_long_edges = 0;        // sheet edges halved for being over long_edge_factor
                                        // median edges
  uint32_t collapsed_edges = 0;         // sheet edges shorter than
                                        // PlcOptions::short_edge_voxels, collapsed
  uint32_t mended_contacts = 0;         // sheet vertices moved onto another sheet they
                                        // nearly touched (PlcOptions::contact_voxels)
  uint32_t mended_edge_contacts = 0;    // pairs of sheet edges passing that close, joined
                                        // where they pass closest (MendEdgeContacts)
  uint32_t unmended_contacts = 0;       // such vertices left where they are: the move made
                                        // a clash, or a rim along another sheet stayed
  std::vector<Vec3> contact_places;     // where the first of those are, physical units
  uint32_t joined_touches = 0;          // sheet vertices lying on another sheet triangle's
                                        // edge or face, joined to it (JoinTouches)
  uint32_t box_points = 0;              // points seeded on the box's edges and faces
                                        // (PlcOptions::seed_box), after the sheets' vertices
  uint32_t seed_points = 0;             // lattice points seeded off the sheets (the last
                                        // vertices, on no facet)
  double lattice_spacing = 0;           // physical units, the finest level's; 0 without
                                        // seeding
  uint32_t lattice_levels = 0;          // levels of the graded lattice used
  double lattice_coarsest = 0;          // the last level's spacing, physical units

  // The figures by name (snapped_vertices, ..., lattice_spacing), for the report.
  nlohmann::json Fields() const;
};

struct Plc : PlcStats {
  std::vector<Vec3> vertices;          // physical units
  std::vector<PlcFacet> facets;        // the 6 box faces first, then one per sheet triangle
  std::vector<Face> sheet_triangles;   // the sheet triangles as kept, in `vertices`
  std::vector<int32_t> sheet_piece;    // per kept sheet triangle
  std::vector<float> sheet_thickness;  // per kept sheet triangle, voxels
  Vec3 box_lo, box_hi;                 // physical
  double voxel_length = 1;             // physical

  // The PLC as a TetGen .poly file (0-based numbering).
  std::string ToPoly() const;
};

struct PlcOptions {
  double snap_voxels = 0.75;  // vertices this close to a box face move onto it
  // Vertices farther off a box face than snap_voxels but within this move onto it too,
  // unless that makes one of their triangles cut another (such a vertex stays where it
  // is). A sheet vertex just off a box face pins slivers between the two that nothing
  // after can mend; a sheet that ends within a voxel or so of the box reaches it in the
  // image. 0 (or below snap_voxels): only snap_voxels.
  double snap_clear_voxels = 1.5;
  double merge_voxels = 1e-3;  // vertices this close merge
  // Sheet triangles that cut through each other are untangled first, by moving a vertex of
  // the pair at most this many voxels or flipping one of its edges (UntangleStats); 0: none.
  double untangle_voxels = 1.0;
  // Clashes untangling leaves (a sheet crumpled within a voxel or two, which neither moves,
  // flips, splits nor a patch mends: 3 of the 140 runs of the volume mesh sweep) are
  // removed, the smaller triangle of each pair, and the report says how many and their
  // area; false: the job fails, naming them.
  bool repair = true;
  // Sheet triangles TetGen must keep are improved first, since a thin or flat one forces
  // tiny tetrahedra and slivers: an edge between two triangles of one piece whose normals
  // are within flip_fold_degrees is flipped where that raises their smallest angle (0:
  // no flips, the sheet triangles are kept as given). A flat triangle, with an angle over
  // cap_degrees, has no plane to speak of: its long edge is flipped whatever the fold, or,
  // where that cannot be and it lies on the rim (it covers almost nothing), it is dropped.
  double flip_fold_degrees = 15.0;
  // A slit (three rim edges framing no triangle, one corner's angle over cap_degrees) is
  // closed by splitting the face on its long edge at that corner.
  double cap_degrees = 160.0;
  // A sheet triangle that runs within overlap_voxels of another one's interior, their
  // planes within overlap_degrees of parallel, forces slivers in the thin wedge between
  // them; the one of the two on a sheet's rim (a fragment lying on a sheet, a rim running
  // over another sheet) is dropped. 0: keep them all.
  double overlap_voxels = 0.5;
  double overlap_degrees = 25.0;
  // A sheet edge that leaves a corner of a sheet face within wedge_degrees of the face's
  // plane, running over the face (a sheet ending or folding just off another one at a
  // shared vertex), makes a wedge that TetGen fills with tetrahedra whose dihedral angle
  // is as small as the wedge, and that nothing after can mend. The edge's far end moves
  // straight away from the face's plane until the wedge is wedge_degrees wide, by at most
  // wedge_voxels, where that widens the narrowest wedge around it and makes no clash;
  // vertices on the box stay (bench/RESULTS.md). A sheet face meeting a box face along an
  // edge within wedge_degrees (a sheet grazing the box) has its third corner moved off the
  // box face the same way. 0 for either: no moves.
  double wedge_degrees = 12.0;
  double wedge_voxels = 1.0;
  // A junction line (edges of three or more sheet triangles) that zig-zags lays a triangle
  // between two of its links onto one of the sheets at a degree or two; where a wedge
  // around a junction vertex is under wedge_degrees, the vertex moves onto the line between
  // its two neighbours on the junction, by at most junction_voxels, where that widens the
  // wedge and makes no clash: the triangle between the links goes (StraightenJunctions).
  // 0: none.
  double junction_voxels = 2.0;
  // A sheet vertex within this many voxels of another sheet's triangle (off its own) moves
  // onto it: onto its corner, merging the two; onto its edge or into it, splitting the
  // triangles there. Left apart, the two sheets pin a layer of tetrahedra as flat as the
  // gap is narrow that nothing after can mend. A move that makes triangles clash is not
  // made, and the report names the place. 1.5 voxels, as for the box (snap_clear_voxels):
  // at 0.75 the 192^3 phantom kept 8.12° and the rough network 7.59°, at 1.5 11.03° and
  // 10.00° (bench/RESULTS.md). 0: none.
  double contact_voxels = 1.5;
  // Sheet edges passing within contact_voxels of each other are joined, so a rim running
  // along another sheet is zipped onto it (MendEdgeContacts, then its vertices moved).
  // Where TetGen refuses the zipped PLC, BuildVolumeMesh meshes again without.
  bool zip_rims = true;
  // Sheet edges shorter than this many voxels collapse to their midpoint, where that makes
  // no fold, hole or clash: TetGen must keep every sheet edge, and one of 1.7 voxels among
  // edges of 25 (the paper phantom at r = 15) pins a tetrahedron of 5.55°. 0: none.
  double short_edge_voxels = 2.0;
  // Sheet edges longer than this many times the sheets' median edge are halved (in their
  // triangle's plane, so the sheets keep their shape) before TetGen, which may split none
  // (-Y): a mid-surface keeps its flat regions in triangles tens of voxels long, whose
  // edges run past the finely spaced points near junctions and the box and pin slivers
  // there (DPM at r = 3: a sheet edge 100 voxels long along the box, 3.5°). 0: none.
  double long_edge_factor = 2.0;
  // Seeds TetGen with a graded body-centred cubic lattice of points off the sheets, its
  // spacing this many times the sheets' median edge next to them, growing outward at
  // `grading` (never past a quarter of the box's thinnest side). The lattice's tetrahedra
  // are near-ideal (60° smallest dihedral angle), so the mean quality rises
  // (bench/RESULTS.md). 0: none, TetGen places all points.
  double lattice = 0.85;
  // How fast the lattice's spacing grows with the distance from the sheets: each level
  // doubles the spacing after 1 / grading spacings of its own (1: every spacing). Higher
  // grades faster, with fewer tetrahedra and a wider layer of worse ones where two levels
  // meet. At 1 the benchmark volumes took about 40% fewer tetrahedra than at 0.4 (issue
  // 41); at 2, with fewer vertices inserted by the improvement, the volume mesh sweep's
  // median went from 21 to 13 tetrahedra per sheet triangle, every run's smallest angle
  // still at 10° or more where it was (bench/RESULTS.md, issue 65).
  double grading = 2.0;
  // Seeds the box's edges and faces with points, graded like the lattice (its spacing, or
  // the median edge without one), embedded in the box facets. For a TetGen that may add
  // no points on facets (-Y), which would otherwise keep each box face as two triangles.
  bool seed_box = false;
};

// A pair of sheet triangles (indices into the input mesh) that cut through each other.
struct Clash {
  uint32_t a = 0, b = 0;
  std::array<Vec3, 3> ta, tb;  // their corners, physical units
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_PLC_TYPES_H_
