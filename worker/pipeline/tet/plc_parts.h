// Internal to the PLC (plc*.cc): the sheet triangles as the PLC keeps and mends them, and
// the steps BuildPlc runs: snapping onto the box (plc_snap.cc), mending the sheets
// (plc_repair.cc) and seeding points off them (plc_seeding.cc).
#ifndef SHEETMESH_WORKER_PIPELINE_TET_PLC_PARTS_H_
#define SHEETMESH_WORKER_PIPELINE_TET_PLC_PARTS_H_

#include <array>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/status/status.h"
#include "worker/pipeline/mesh/spatial_grid.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/tet/plc_types.h"

namespace sheetmesh {

// A sheet vertex at distance d from another sheet or a box face that it reaches along the
// sheets within kReachFactor d / sin(kWedgeKeptDegrees) (the way to a corner there, and on
// to the nearest point) meets it there in a wedge of a junction, a fold or the box
// — at an angle of at least that, the rock's — not across a gap: the mends leave it where
// it is, since moving it would only narrow the wedge. Through a junction at angle a the way
// is (1 + cos a) d / sin a along straight lines; the factor allows for paths along edges.
constexpr double kWedgeKeptDegrees = 10.0;
constexpr double kReachFactor = 2.5;
// A rim vertex near another sheet whose faces all stand on it at this angle or more is
// moved onto it however soon the sheets reach it (MendContacts): a T-junction left short,
// not a wedge.
constexpr double kSteepRimDegrees = 30.0;
// The vertices within path length `limit` of u along the edges of `faces` (faces_of: each
// vertex's faces), with their path lengths.
std::vector<std::pair<uint32_t, double>> ReachAlongSheets(
    uint32_t u, double limit, const std::vector<Vec3>& v, const std::vector<Face>& faces,
    const std::vector<std::vector<uint32_t>>& faces_of);

// Face k of the box: axis k / 2, low side when k is even. Bit k of an on_face mask.
inline int Axis(int face) { return face / 2; }
inline bool Low(int face) { return face % 2 == 0; }

// The sheet triangles the PLC keeps, with where each came from.
struct SheetTriangles {
  std::vector<Face> faces;
  std::vector<uint32_t> source;  // input face
  std::vector<int32_t> piece;
  std::vector<float> thickness;
};

// `s` without the triangles marked in `drop`.
SheetTriangles Without(const SheetTriangles& s, const std::vector<uint8_t>& drop);

// Each vertex's faces, each edge's faces (by EdgeKey), and the faces in a grid by their
// boxes grown by `grow` (cells as long as the longest edge, or grow): what the mends look
// things up in.
struct SheetIndex {
  std::vector<std::vector<uint32_t>> faces_of;
  absl::flat_hash_map<uint64_t, std::vector<uint32_t>> edge_faces;
  SpatialGrid grid{1.0};
};
SheetIndex IndexSheets(const SheetTriangles& s, const std::vector<Vec3>& v, double grow);

// The corner of face t that is not on its edge a-b.
inline uint32_t Opposite(const Face& t, uint32_t a, uint32_t b) {
  return t[0] != a && t[0] != b ? t[0] : t[1] != a && t[1] != b ? t[1] : t[2];
}
// Face t split at w on its edge a-b, keeping its orientation: the half with a, then the
// half with b.
std::array<Face, 2> HalvesAt(const Face& t, uint32_t a, uint32_t b, uint32_t w);
// The wedges between the facets on an edge of direction e, given the unit directions across
// the edge into each (`sides`): going round the edge from one side to the next, each gap in
// degrees with the unit direction halfway through it.
struct EdgeWedge {
  double degrees = 0;
  Vec3 middle;
};
std::vector<EdgeWedge> WedgesAroundEdge(const Vec3& e, const std::vector<Vec3>& sides);

// Splits each face of on_edge (the faces on edge a-b) at vertex w, keeping its orientation:
// the face keeps the half with a, the half with b is appended with its attributes; both
// get `by` in owner (one entry per face).
void SplitEdgeFaces(uint32_t a, uint32_t b, uint32_t w, const std::vector<uint32_t>& on_edge,
                    int by, SheetTriangles& s, std::vector<int>& owner);

// Makes the kept changes of a round on copies of the sheets: owner gets, per face, the
// position in `kept` of the change that made or moved it (-1: none).
using ApplyChanges = std::function<void(const std::vector<size_t>& kept, SheetTriangles& s,
                                        std::vector<Vec3>& v, std::vector<int>& owner)>;
// Makes a round's n changes together; those whose faces then clash, or repeat a triangle
// (TetGen aborts on it), are left out (appended to *left_out, when not null) and the rest
// made again, at most six times; none is made where a clash is no change's. Returns how
// many were made.
uint32_t ApplyLeavingClashesOut(size_t n, const ApplyChanges& apply, SheetTriangles& s,
                                std::vector<Vec3>& v, std::vector<size_t>* left_out);

// The sheets on the box: vertices (index coordinates) moved onto the box faces they are
// near, near-duplicates merged, the triangles still triangles and off the box faces,
// flipped for better shapes (PlcOptions::flip_fold_degrees).
struct SnappedSheets {
  std::vector<Vec3> v;           // per input vertex
  std::vector<uint8_t> on_face;  // per vertex, bit k: on box face k
  std::vector<uint32_t> rep;     // per vertex: the vertex it merged into (itself if none)
  SheetTriangles st;             // on the representatives
  bool checked_clean = false;    // the last round's triangles were found not to clash
  std::vector<uint8_t> held;     // per vertex: HeldAtJunctions of the sheets as given
};

// The corners of every sheet triangle on a junction (an edge of three or more triangles, or
// of two of different pieces): where sheets meet, at the angle the surface gives them, the
// repairs below neither move these vertices nor flip or collapse these triangles' edges, so
// the junction reaches TetGen as the surface drew it. One entry per vertex of `vertices`.
std::vector<uint8_t> HeldAtJunctions(const SheetTriangles& s, size_t vertices);

// Vertices within snap_voxels of a box face always snap onto it; those out to
// snap_clear_voxels snap unless that makes their triangles cut another sheet's (then they
// stay off it and the snapping is redone, up to five rounds). Sets stats' snapped, held,
// merged, dropped, flipped and cap counts.
SnappedSheets SnapToBox(const TriangleMesh& sheets, const Vec3& lo, const Vec3& hi,
                        const PlcOptions& options, PlcStats* stats);

// What Untangle did.
struct UntangleStats {
  uint32_t found_pairs = 0;      // clashing pairs before
  uint32_t remaining_pairs = 0;  // after
  uint32_t moved_vertices = 0;
  uint32_t flipped_edges = 0;
  uint32_t split_crossings = 0;         // pairs crossing beyond a shared corner, split to
                                        // meet in an edge
  uint32_t thin_splits = 0;             // of those, split with pieces under kMinSplitAngle
  uint32_t retriangulated_patches = 0;  // patches replaced by a fan (RetriangulatePatch)
  double max_move = 0;                  // voxels
};

// Mends sheet triangles that cut through each other (FindSelfIntersections' rules) by local
// moves that keep every triangle: a vertex of a clashing pair moves by at most
// max_move_voxels, and where nothing at that size mends a pair, by up to three times that
// (toward the middle of its neighbours, or off the other triangle's plane; last, the faces
// of one piece around the pair re-triangulated as a fan from their outline's middle;
// a vertex on one box face stays in it, one on a box edge or corner stays), else an edge of
// the pair is flipped, each only where it leaves its faces clashing with none, no sliver
// (1 degree) and none turned over. Rounds until none clash or none mends.
UntangleStats Untangle(SheetTriangles& st, std::vector<Vec3>& v,
                       const std::vector<uint8_t>& on_face, double max_move_voxels);

// Sheet triangles that cut through each other: listed in `clashes` (when not null, in
// physical units); kFailedPrecondition naming the first five unless options.repair, which
// drops the smaller of each pair (stats->repaired_triangles; of a body's wall, in
// `body_pieces`, and a sheet, the sheet's) and fails only if clashes remain. With `checked_clean`
// the check is skipped (the snapping just made it).
absl::Status ResolveClashes(const std::vector<Vec3>& v, bool checked_clean,
                            const std::vector<int32_t>& body_pieces, const Placement& placement,
                            const PlcOptions& options, SheetTriangles* st, PlcStats* stats,
                            std::vector<Clash>* clashes);

// Flips sheet edges where that gives better triangles and drops flat rim triangles,
// keeping only what makes no clash. Returns (flips, drops).
// No flip touches a `held` vertex.
std::pair<uint32_t, uint32_t> FlipSheetTriangles(SheetTriangles& st, const std::vector<Vec3>& v,
                                                 const std::vector<uint8_t>& on_face,
                                                 const std::vector<uint8_t>& held,
                                                 double fold_degrees, double cap_degrees);
// Closes slits framed by three rim edges. Returns the number closed.
uint32_t CloseSlits(SheetTriangles& s, const std::vector<Vec3>& v, double min_degrees);
// Drops rim triangles that lie on another sheet; an edge on a box face (both ends on one,
// `on_face`) is no rim, and two triangles that share a `held` vertex (a junction's) meet
// there at the junction's angle, however small. Returns the number dropped.
uint32_t DropOverlaps(SheetTriangles& s, const std::vector<Vec3>& v,
                      const std::vector<uint8_t>& on_face, const std::vector<uint8_t>& held,
                      double gap, double max_degrees);
// Opens narrow wedges (below min_degrees) between a sheet face and a sheet edge, moving
// vertices in `v`; a junction at a true angle of min_degrees or more is not touched, and
// one narrower is opened like any wedge (holding its vertices kept NETL's 4.2-degree
// wedge at r = 5, bench/RESULTS.md issue 64). Returns the number of vertices moved.
uint32_t OpenWedges(const SheetTriangles& st, const std::vector<uint8_t>& on_face,
                    double min_degrees, double max_move, std::vector<Vec3>& v);
// Straightens junction lines (chains of edges of three or more sheet triangles) where they
// zig-zag (plc_junctions.cc): a vertex u of a chain between a and c, off the box, with a
// wedge under min_degrees at an edge of its faces, moves onto the segment a-c (at most
// max_move) where that widens the narrowest wedge there; the triangle (a, u, c) goes and
// the faces on edge a-c are split at u. Changes whose faces clash are left out. Returns
// the number of vertices moved.
// Opens wedges under min_degrees between two faces on an edge (sheets meeting, or one
// folding, at a narrow angle there): one face's far corner turns about the edge's line away
// from the other, by at most max_move from where it began, where that widens the narrowest
// wedge around it; vertices on the box stay; moves whose faces clash are left out. Returns
// the number of vertices moved.
uint32_t OpenDihedralWedges(SheetTriangles& st, std::vector<Vec3>& v,
                            const std::vector<uint8_t>& on_face, double min_degrees,
                            double max_move);
uint32_t StraightenJunctions(SheetTriangles& st, std::vector<Vec3>& v,
                             const std::vector<uint8_t>& on_face, double min_degrees,
                             double max_move);

// A point on the box's surface: on the faces whose bits are set (bit `face`, as on_face).
struct BoxPoint {
  Vec3 p;
  uint8_t on_face = 0;
};

// Moves each sheet vertex (off the box) that lies within gap of a triangle not its own onto
// it: onto its corner (merging the two), its edge or its interior (splitting the triangles
// there), nearest first, leaving out moves that make triangles clash, the `held` vertices
// and the wedges of junctions and folds (a triangle reached along the sheets about as soon
// as across). Returns the number mended; the vertices left for a clash go into *unmended
// (when not null).
// With zip_rims, each round first joins sheet edges that pass within gap of each other
// (MendEdgeContacts), which makes the vertices of a rim running along another sheet
// point contacts, and a rim vertex whose faces stand steeply on the sheet it nearly touches
// moves onto it however soon the sheets reach it; those joins are counted into
// *edge_contacts (when not null). New vertices get on_face 0.
uint32_t MendContacts(SheetTriangles& s, std::vector<Vec3>& v, std::vector<uint8_t>& on_face,
                      const std::vector<uint8_t>& held, double gap, bool zip_rims,
                      std::vector<Vec3>* unmended, uint32_t* edge_contacts = nullptr);

// Joins pairs of sheet edges that pass within gap of each other away from their corners
// (closer than gap to none of them), not side by side, not edges of neighbouring faces and
// not a wedge of a junction or fold (the rule of kReachFactor): both split where they pass
// closest, at one new vertex (on the line of the edge with more faces; halfway between
// equals). Joins that make triangles clash or repeat are left. One round, each face in one
// join; returns the number joined.
uint32_t MendEdgeContacts(SheetTriangles& s, std::vector<Vec3>& v, std::vector<uint8_t>& on_face,
                          double gap);

// Closes the caps the mends left (a sheet triangle whose corner c has an angle over
// cap_degrees, c nearly on the long edge a-b): c moves onto a-b, by at most max_move, the
// cap goes and every other face on a-b is split at c, so the sheet keeps its topology and
// loses a sliver of area. A cap at a junction is closed as well (the flips before leave
// those). TetGen must otherwise fill the cap's flat wedge with slivers, and its exact
// intersection test finds a cap folded onto a neighbour where ours cannot. Moves that
// make a clash are left out. Returns the number closed.
uint32_t CloseCaps(SheetTriangles& s, std::vector<Vec3>& v, const std::vector<uint8_t>& on_face,
                   double cap_degrees, double max_move);

// Drops the sheet triangles whose corners lie on a line (within eps voxels: no area, one
// corner on the long edge), which the mends can leave. Returns the number dropped.
uint32_t DropFlatTriangles(SheetTriangles& s, const std::vector<Vec3>& v, double eps);

// Joins each sheet vertex that lies on another sheet triangle (within eps voxels of its
// edge or its interior, a T that the mends before left or made) to it: the edge's faces,
// or the face, split there. TetGen takes a vertex on a facet's edge for a crossing and
// aborts. Returns the number joined.
uint32_t JoinTouches(SheetTriangles& s, std::vector<Vec3>& v, double eps);

// Bisects sheet triangles (conforming longest-edge bisection, each new vertex an edge's
// midpoint, so the sheets keep their shape) until no edge is longer than max_edge (voxels).
// A midpoint lies on the box faces both ends of its edge lie on (on_face grows with v).
// Returns the number of edges split; none for max_edge <= 0.
uint32_t SplitLongSheetEdges(double max_edge, std::vector<Vec3>* vertices,
                             std::vector<uint8_t>* on_face, SheetTriangles* st);

// Collapses sheet edges shorter than max_length (voxels), shortest first, each to its
// midpoint (or onto its end on the box), where that makes no fold or hole and turns no
// face by over 30 degrees (one on a junction by over 1); a vertex on a junction stays, or
// goes along it where the junction runs straight on; a round that makes a clash is undone.
// Returns the number.
uint32_t CollapseShortEdges(SheetTriangles& s, std::vector<Vec3>& v,
                            const std::vector<uint8_t>& on_face, double max_length);

// The graded lattice's levels: level l has spacing spacing · 2^l and fills the distances
// from the sheets in [inner[l], outer[l]) (the last level: out to infinity).
struct LatticeLevels {
  std::vector<double> spacing, inner, outer;
  // The spacing at distance d from the sheets (0 nearer than the first level's inner edge,
  // where TetGen places the points).
  double SpacingAt(double d) const;
};
LatticeLevels GradeLattice(const Vec3& box_lo, const Vec3& box_hi, double spacing, double grading);

// Seed points off the sheets, a graded lattice (plc_seeding.cc).
std::vector<Vec3> SeedLattice(const Plc& plc, const LatticeLevels& levels);
// Points on the box's edges and faces, graded like the lattice.
std::vector<BoxPoint> SeedBox(const Plc& plc, const LatticeLevels& levels);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_PLC_PARTS_H_
