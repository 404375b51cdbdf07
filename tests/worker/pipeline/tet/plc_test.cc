#include "worker/pipeline/tet/plc.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "tests/testing/status_matchers.h"
#include "tests/worker/pipeline/tet/tet_test_shapes.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/tetgen_runner.h"
#include "worker/pipeline/tet/volume_mesher.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::Append;
using ::sheetmesh::testing::Square;

// Two triangles of a flat quad split along its long diagonal a-b (a thin pair), with the
// fourth corner d lifted by `lift` out of the plane; pieces and thicknesses given. c lies
// `bulge` off a-b: at 1.5 its angle is ~163 degrees (a flat triangle), at 2.5 ~152.
TriangleMesh ThinPair(double lift, int32_t piece_f, int32_t piece_g, double bulge = 1.5) {
  TriangleMesh m;
  m.vertices = {{10, 10, 20}, {30, 10, 20}, {20, 10 + bulge, 20}, {20, 8.5, 20 + lift}};  // a b c d
  m.faces = {{0, 1, 2}, {1, 0, 3}};
  m.face_piece = {piece_f, piece_g};
  m.face_thickness_voxels = {2, 4};
  return m;
}

bool HasEdge(const Plc& plc, const Vec3& p, const Vec3& q) {
  for (const Face& t : plc.sheet_triangles) {
    for (int k = 0; k < 3; ++k) {
      const Vec3 a = plc.vertices[t[k]], b = plc.vertices[t[(k + 1) % 3]];
      if ((Norm(a - p) < 1e-9 && Norm(b - q) < 1e-9) || (Norm(a - q) < 1e-9 && Norm(b - p) < 1e-9))
        return true;
    }
  }
  return false;
}

// Triangle A lies in the plane z = 12; triangle H, in the plane x = y, shares A's corner O
// and its edge O-W runs over A 0.5 voxels below A's plane (3.4 degrees off it, its
// projection inside A's angle at O).
TriangleMesh NarrowWedge() {
  TriangleMesh m;
  m.vertices = {{5, 5, 12},
                {14, 5, 12},
                {5, 14, 12},  // A: O and two more
                {11, 11, 11.5},
                {8, 8, 4}};  // H: O, W, and a corner far below
  m.faces = {{0, 1, 2}, {0, 3, 4}};
  m.face_piece = {0, 0};
  m.face_thickness_voxels = {1, 1};
  return m;
}

// The vertex of `plc` nearest to p.
Vec3 Nearest(const Plc& plc, const Vec3& p) {
  return *std::min_element(
      plc.vertices.begin(), plc.vertices.end(),
      [&](const Vec3& a, const Vec3& b) { return Norm2(a - p) < Norm2(b - p); });
}

// Meshes `sheets` with the options `with` (a PLC step on) and `without` (off) into *r and
// *off; the first must conform, fill the box and have the better worst tetrahedron.
void MeshWithAndWithout(const TriangleMesh& sheets, const Dims& dims, const VolumeMeshOptions& with,
                        const VolumeMeshOptions& without, VolumeMeshResult* r,
                        VolumeMeshResult* off) {
  SM_ASSERT_OK_AND_ASSIGN(*r, BuildVolumeMesh(sheets, dims, {}, with));
  SM_ASSERT_OK_AND_ASSIGN(*off, BuildVolumeMesh(sheets, dims, {}, without));
  EXPECT_EQ(r->conformity.conforming, r->conformity.sheet_triangles);
  EXPECT_NEAR(r->quality.volume, r->box_volume, 1e-9 * r->box_volume);
  EXPECT_GT(r->quality.min_dihedral.min, off->quality.min_dihedral.min);
}

// A sheet in the plane z = 10 with a slit: triangle A's rim edge a-b, and the rim a-c-b of
// the triangles below it, c 0.1 voxels off a-b (its angle 178 degrees) and 0.05 above the
// plane.
TriangleMesh Slit() {
  TriangleMesh m;
  m.vertices = {{5, 10, 10},     {15, 10, 10}, {10, 16, 10},  // a, b, x
                {9, 9.9, 10.05}, {7, 4, 10},   {13, 4, 10}};  // c, y, z
  m.faces = {{0, 1, 2}, {0, 4, 3}, {3, 5, 1}, {3, 4, 5}};
  m.face_piece.assign(4, 0);
  m.face_thickness_voxels.assign(4, 1);
  return m;
}

TEST(PlcTest, AThinPairOfCoplanarTrianglesIsFlipped) {
  SM_ASSERT_OK_AND_ASSIGN(Plc plc, BuildPlc(ThinPair(0, 0, 0), {40, 20, 40}, {}));
  EXPECT_EQ(plc.flipped_edges, 1u);
  ASSERT_EQ(plc.sheet_triangles.size(), 2u);
  EXPECT_FALSE(HasEdge(plc, {10, 10, 20}, {30, 10, 20}));
  EXPECT_TRUE(HasEdge(plc, {20, 11.5, 20}, {20, 8.5, 20}));
  // Both halves of the flipped quad carry the pair's area-weighted thickness (equal areas).
  EXPECT_FLOAT_EQ(plc.sheet_thickness[0], 3.f);
  EXPECT_FLOAT_EQ(plc.sheet_thickness[1], 3.f);
  // Better triangles, and the same surface: the area is unchanged.
  double area = 0, min_angle = 180;
  for (const Face& t : plc.sheet_triangles) {
    const Triangle c = {plc.vertices[t[0]], plc.vertices[t[1]], plc.vertices[t[2]]};
    area += Area(c);
    min_angle = std::min(min_angle, MinAngleDegrees(c));
  }
  EXPECT_NEAR(area, 30.0, 1e-9);
  EXPECT_GT(min_angle, 16.0);
}

TEST(PlcTest, FlipsKeepPiecesFoldsAndCanBeTurnedOff) {
  PlcOptions off;
  off.flip_fold_degrees = 0;
  SM_ASSERT_OK_AND_ASSIGN(Plc kept, BuildPlc(ThinPair(0, 0, 0), {40, 20, 40}, {}, off));
  EXPECT_EQ(kept.flipped_edges, 0u);
  EXPECT_TRUE(HasEdge(kept, {10, 10, 20}, {30, 10, 20}));
  SM_ASSERT_OK_AND_ASSIGN(Plc pieces, BuildPlc(ThinPair(0, 0, 1, 2.5), {40, 20, 40}, {}));
  EXPECT_EQ(pieces.flipped_edges, 0u);  // two pieces meeting along an edge keep it
  EXPECT_TRUE(HasEdge(pieces, {10, 10, 20}, {30, 10, 20}));
  // A fold (d lifted 3 voxels: the normals are ~60 degrees apart) is a shape, not noise.
  SM_ASSERT_OK_AND_ASSIGN(Plc fold, BuildPlc(ThinPair(3, 0, 0, 2.5), {40, 20, 40}, {}));
  EXPECT_EQ(fold.flipped_edges, 0u);
  EXPECT_TRUE(HasEdge(fold, {10, 10, 20}, {30, 10, 20}));
  EXPECT_EQ(fold.sheet_triangles.size(), 2u);
}

TEST(PlcTest, AFlatTriangleIsFlippedAwayAcrossAFoldOrDroppedOnTheRim) {
  // c lies 1.5 voxels off the 20-voxel edge a-b (a ~163 degree angle), and g = b a d is
  // folded ~60 degrees away: f's plane says nothing about the sheet, and TetGen would
  // have to follow it. The flip trades f and g for two halves of g.
  SM_ASSERT_OK_AND_ASSIGN(Plc fold, BuildPlc(ThinPair(3, 0, 0), {40, 20, 40}, {}));
  EXPECT_EQ(fold.flipped_edges, 1u);
  EXPECT_EQ(fold.dropped_caps, 0u);
  ASSERT_EQ(fold.sheet_triangles.size(), 2u);
  EXPECT_TRUE(HasEdge(fold, {20, 11.5, 20}, {20, 8.5, 23}));
  std::vector<Vec3> normals;
  for (const Face& t : fold.sheet_triangles) {
    const Triangle c = {fold.vertices[t[0]], fold.vertices[t[1]], fold.vertices[t[2]]};
    EXPECT_LT(AngleRangeDegrees(c).second, 160.0);
    normals.push_back(AreaVector(c));
  }
  EXPECT_LT(AngleDegrees(normals[0], normals[1]), 15.0);  // no new fold
  // Where the two belong to different pieces no flip applies: f has edges on the rim, covers
  // almost nothing and is dropped, its obtuse corner with it.
  PlcOptions unseeded;
  unseeded.lattice = 0;
  SM_ASSERT_OK_AND_ASSIGN(Plc pieces, BuildPlc(ThinPair(3, 0, 1), {40, 20, 40}, {}, unseeded));
  EXPECT_EQ(pieces.flipped_edges, 0u);
  EXPECT_EQ(pieces.dropped_caps, 1u);
  ASSERT_EQ(pieces.sheet_triangles.size(), 1u);
  EXPECT_EQ(pieces.vertices.size(), 8u + 3u);  // box corners and g's corners
  // With the flips off, the sheet triangles stay as given.
  PlcOptions off;
  off.flip_fold_degrees = 0;
  SM_ASSERT_OK_AND_ASSIGN(Plc kept, BuildPlc(ThinPair(3, 0, 0), {40, 20, 40}, {}, off));
  EXPECT_EQ(kept.sheet_triangles.size(), 2u);
  EXPECT_EQ(kept.flipped_edges + kept.dropped_caps, 0u);
}

TEST(PlcTest, AFlatTriangleOnTheRimIsDropped) {
  // A good triangle and, beside it on a short edge, a flat cap (largest angle ~170
  // degrees) whose long edge is on the sheet's rim: no flip can mend it.
  TriangleMesh m;
  m.vertices = {{10, 10, 20}, {30, 10, 20}, {20, 10.9, 20}, {12, 20, 20}};  // a b c e
  m.faces = {{0, 2, 3}, {0, 1, 2}};
  m.face_piece = {0, 0};
  m.face_thickness_voxels = {3, 3};
  PlcOptions o;
  o.flip_fold_degrees = 15;
  SM_ASSERT_OK_AND_ASSIGN(Plc plc, BuildPlc(m, {40, 30, 40}, {}, o));
  // The cap covers almost nothing and goes.
  EXPECT_EQ(plc.dropped_caps, 1u);
  ASSERT_EQ(plc.sheet_triangles.size(), 1u);
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult r, BuildVolumeMesh(m, {40, 30, 40}, {}, {}));
  EXPECT_EQ(r.dropped_caps, 1u);
  EXPECT_EQ(r.conformity.conforming, 1u);
}

TEST(PlcTest, AFragmentLyingOnASheetIsDropped) {
  // A 4 x 4 square sheet at z = 10 and a lone triangle 0.2 voxel above it, tilted by ~2
  // degrees: TetGen would fill the 0.2-voxel wedge between them with slivers.
  TriangleMesh fragment;
  fragment.vertices = {{6, 6, 10.2}, {11, 6, 10.2}, {6, 11, 10.37}};
  fragment.faces = {{0, 1, 2}};
  fragment.face_piece = {1};
  fragment.face_thickness_voxels = {2};
  const TriangleMesh m = Append(Square(4, 16, 10, 4), fragment);
  SM_ASSERT_OK_AND_ASSIGN(Plc plc, BuildPlc(m, {20, 20, 20}, {}));
  EXPECT_EQ(plc.dropped_overlaps, 1u);
  ASSERT_EQ(plc.sheet_triangles.size(), 32u);
  for (int32_t piece : plc.sheet_piece) EXPECT_EQ(piece, 0);
  PlcOptions keep;  // off: kept (and TetGen meshes the wedge)
  keep.overlap_voxels = 0;
  keep.contact_voxels = 0;
  keep.long_edge_factor = 0;  // the fragment's long edge kept whole
  SM_ASSERT_OK_AND_ASSIGN(Plc kept, BuildPlc(m, {20, 20, 20}, {}, keep));
  EXPECT_EQ(kept.dropped_overlaps, 0u);
  EXPECT_EQ(kept.sheet_triangles.size(), 33u);
  // The volume mesh without the fragment has no sliver from it, and says what went.
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult r, BuildVolumeMesh(m, {20, 20, 20}, {}, {}));
  EXPECT_EQ(r.dropped_overlaps, 1u);
  EXPECT_EQ(r.conformity.conforming, 32u);
  // Kept (and nothing else to mend it: no sheet vertex moves, no refinement round), its
  // sliver stays.
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult with, BuildVolumeMesh(m, {20, 20, 20}, {}, [] {
                            VolumeMeshOptions o;
                            o.plc.overlap_voxels = 0;
                            o.plc.contact_voxels = 0;
                            o.plc.long_edge_factor = 0;
                            o.improve.sheet_move_voxels = 0;
                            o.sliver_rounds = 0;
                            return o;
                          }()));
  EXPECT_EQ(with.conformity.conforming, 33u);
  EXPECT_GT(r.quality.min_dihedral.min, with.quality.min_dihedral.min);
}

TEST(PlcTest, SheetsMeetingAtAnAngleOrFarApartAreNotOverlaps) {
  // A vertical sheet whose rim ends 0.2 voxel above a horizontal one (a T, not parallel),
  // and a parallel sheet 2 voxels above it (beyond the gap): nothing is dropped.
  const TriangleMesh t = Append(Square(4, 16, 10, 4), Square(10.2, 16, 10, 2, 1, 3, 0));
  SM_ASSERT_OK_AND_ASSIGN(Plc tee, BuildPlc(t, {20, 20, 20}, {}));
  EXPECT_EQ(tee.dropped_overlaps, 0u);
  const TriangleMesh parallel = Append(Square(4, 16, 10, 4), Square(6, 12, 12, 2, 1));
  SM_ASSERT_OK_AND_ASSIGN(Plc par, BuildPlc(parallel, {20, 20, 20}, {}));
  EXPECT_EQ(par.dropped_overlaps, 0u);
  // Within a wider gap the parallel sheets do overlap, and rim triangles go.
  PlcOptions wide;
  wide.overlap_voxels = 3;
  SM_ASSERT_OK_AND_ASSIGN(Plc close, BuildPlc(parallel, {20, 20, 20}, {}, wide));
  EXPECT_GT(close.dropped_overlaps, 0u);
  EXPECT_EQ(close.sheet_triangles.size() + close.dropped_overlaps, 40u);
}

TEST(PlcTest, ANarrowWedgeBetweenASheetFaceAndAnEdgeOverItOpens) {
  const Dims dims{20, 20, 20};
  const Vec3 w0(11, 11, 11.5);
  const double in_plane = std::sqrt(72.0);  // |O-W| in A's plane
  PlcOptions base;
  base.lattice = 0;
  // By default the contact mends come first: O-W passes 0.375 voxel under A's edge
  // (14, 5)-(5, 14), and the two edges are joined where they pass closest
  // (plc_contacts_test.cc); the wedge opening is measured with them off.
  SM_ASSERT_OK_AND_ASSIGN(const Plc joined, BuildPlc(NarrowWedge(), dims, {}, base));
  EXPECT_EQ(joined.mended_edge_contacts, 1u);
  EXPECT_EQ(joined.sheet_triangles.size(), 4u);
  base.contact_voxels = 0;
  // W moves 1 voxel (the most it may) straight down: 10.0 degrees.
  SM_ASSERT_OK_AND_ASSIGN(const Plc a, BuildPlc(NarrowWedge(), dims, {}, base));
  EXPECT_EQ(a.opened_wedges, 1u);
  EXPECT_LT(Norm(Nearest(a, w0) - Vec3(11, 11, 10.5)), 1e-12);
  EXPECT_EQ(PlcOptions().wedge_degrees, 12.0);
  EXPECT_EQ(PlcOptions().wedge_voxels, 1.0);
  // Allowed 2 voxels, it moves until the edge stands exactly 12 degrees off A's plane.
  PlcOptions far = base;
  far.wedge_voxels = 2;
  SM_ASSERT_OK_AND_ASSIGN(const Plc b, BuildPlc(NarrowWedge(), dims, {}, far));
  const Vec3 w = Nearest(b, {11, 11, 10});
  EXPECT_NEAR(w.z, 12 - in_plane * std::tan(12 * std::numbers::pi / 180), 1e-9);
  EXPECT_EQ(w.x, 11);
  EXPECT_EQ(w.y, 11);
  EXPECT_NEAR(std::asin((12 - w.z) / Norm(w - Vec3(5, 5, 12))) * 180 / std::numbers::pi, 12, 1e-9);
  // Switched off, nothing moves.
  PlcOptions off = base;
  off.wedge_degrees = 0;
  SM_ASSERT_OK_AND_ASSIGN(const Plc c, BuildPlc(NarrowWedge(), dims, {}, off));
  EXPECT_EQ(c.opened_wedges, 0u);
  EXPECT_LT(Norm(Nearest(c, w0) - w0), 1e-12);
  // Triangle G (in the plane z = 10) crosses the plane x = y just beyond H; W's move would
  // swing H's edge W-(8, 8, 4) through it, so W stays.
  TriangleMesh blocked = NarrowWedge();
  blocked.vertices.insert(blocked.vertices.end(), {{11.6, 9.6, 10}, {9.6, 11.6, 10}, {13, 13, 10}});
  blocked.faces.push_back({5, 6, 7});
  blocked.face_piece.push_back(1);
  blocked.face_thickness_voxels.push_back(1);
  for (const PlcOptions& o : {base, far}) {
    SM_ASSERT_OK_AND_ASSIGN(const Plc d, BuildPlc(blocked, dims, {}, o));
    EXPECT_EQ(d.opened_wedges, 0u);
    EXPECT_LT(Norm(Nearest(d, w0) - w0), 1e-12);
  }
  // The opened wedge meshes with a better worst tetrahedron (14.0 degrees, 4.8 closed),
  // the sheet's vertices held where the PLC puts them and the sheet triangles as the PLC
  // makes them. (The improvement may move them, the sliver rounds refine them: then the
  // closed wedge's sliver mends too, improve.sheet_move_voxels, sliver_rounds.)
  VolumeMeshOptions opened, closed;
  opened.plc.contact_voxels = closed.plc.contact_voxels = 0;
  opened.improve.sheet_move_voxels = closed.improve.sheet_move_voxels = 0;
  opened.sliver_rounds = closed.sliver_rounds = 0;
  closed.plc.wedge_degrees = 0;
  VolumeMeshResult r, s;
  MeshWithAndWithout(NarrowWedge(), dims, opened, closed, &r, &s);
  EXPECT_EQ(r.opened_wedges, 1u);
}

// A sheet grazing the box: a triangle with its edge a-b on the face z = -0.5 of a 20^3
// box rises 8 degrees off it to O, 16 voxels in (too far off the face to be snapped onto
// it). O moves straight up until the triangle stands 12 degrees off the face (by at most
// plc.wedge_voxels): the narrowest input wedge is the face's, no longer 8 degrees.
TEST(PlcTest, ASheetGrazingABoxFaceIsLiftedOffIt) {
  const Dims dims{20, 20, 20};
  const double tan8 = std::tan(8 * std::numbers::pi / 180);
  const double tan12 = std::tan(12 * std::numbers::pi / 180);
  TriangleMesh m;
  const Vec3 o0(9, 17.5, -0.5 + 16 * tan8);
  m.vertices = {{4, 1.5, -0.5}, {14, 1.5, -0.5}, o0};
  m.faces = {{0, 1, 2}};
  m.face_piece = {0};
  m.face_thickness_voxels = {1};
  PlcOptions base;
  base.lattice = 0;
  PlcOptions off = base;
  off.wedge_degrees = 0;
  SM_ASSERT_OK_AND_ASSIGN(const Plc closed, BuildPlc(m, dims, {}, off));
  EXPECT_EQ(closed.opened_wedges, 0u);
  EXPECT_NEAR(MeasureWedges(closed, 10).narrowest_degrees, 8, 1e-9);
  // By default it moves 1 voxel, the most it may: atan(3.249 / 16) = 11.48 degrees.
  SM_ASSERT_OK_AND_ASSIGN(const Plc a, BuildPlc(m, dims, {}, base));
  EXPECT_EQ(a.opened_wedges, 1u);
  EXPECT_LT(Norm(Nearest(a, o0) - (o0 + Vec3(0, 0, 1))), 1e-12);
  EXPECT_NEAR(MeasureWedges(a, 10).narrowest_degrees,
              std::atan((16 * tan8 + 1) / 16) * 180 / std::numbers::pi, 1e-9);
  // Allowed 2 voxels, exactly 12 degrees.
  PlcOptions far = base;
  far.wedge_voxels = 2;
  SM_ASSERT_OK_AND_ASSIGN(const Plc b, BuildPlc(m, dims, {}, far));
  EXPECT_NEAR(Nearest(b, o0).z, -0.5 + 16 * tan12, 1e-9);
  EXPECT_NEAR(MeasureWedges(b, 10).narrowest_degrees, 12, 1e-9);
}

TEST(PlcTest, ASlitFramedByThreeRimEdgesIsClosed) {
  const Dims dims{20, 20, 20};
  PlcOptions o;
  o.lattice = 0;
  SM_ASSERT_OK_AND_ASSIGN(const Plc plc, BuildPlc(Slit(), dims, {}, o));
  EXPECT_EQ(plc.closed_slits, 1u);
  ASSERT_EQ(plc.sheet_triangles.size(), 5u);
  // A is now (a, c, x) and (c, b, x): a-c and c-b each bound two triangles, a-b none.
  const Vec3 a(5, 10, 10), b(15, 10, 10), c(9, 9.9, 10.05);
  auto count = [&](const Vec3& p, const Vec3& q) {
    int n = 0;
    for (const Face& f : plc.sheet_triangles) {
      int hits = 0;
      for (uint32_t i : f) hits += plc.vertices[i] == p || plc.vertices[i] == q;
      n += hits == 2;
    }
    return n;
  };
  EXPECT_EQ(count(a, c), 2);
  EXPECT_EQ(count(c, b), 2);
  EXPECT_EQ(count(a, b), 0);
  for (const Face& f : plc.sheet_triangles) {
    const Vec3 n =
        Cross(plc.vertices[f[1]] - plc.vertices[f[0]], plc.vertices[f[2]] - plc.vertices[f[0]]);
    EXPECT_GT(n.z, 0) << "orientation kept";
  }
  // The sheet covers what it did, and the slit now too.
  double before = 0, after = 0;
  const TriangleMesh slit = Slit();
  for (const auto& f : slit.faces)
    before += Area({slit.vertices[f[0]], slit.vertices[f[1]], slit.vertices[f[2]]});
  for (const Face& f : plc.sheet_triangles)
    after += Area({plc.vertices[f[0]], plc.vertices[f[1]], plc.vertices[f[2]]});
  EXPECT_NEAR(after, before + Area({a, b, c}), 0.1);  // c is tilted 0.05 off the plane
  // With caps off (180 degrees) the slit stays, and the worst tetrahedron is worse (16.0
  // degrees against 31.4).
  PlcOptions open = o;
  open.cap_degrees = 180;
  SM_ASSERT_OK_AND_ASSIGN(const Plc kept, BuildPlc(Slit(), dims, {}, open));
  EXPECT_EQ(kept.closed_slits, 0u);
  EXPECT_EQ(kept.sheet_triangles.size(), 4u);
  VolumeMeshOptions closed_mesh, open_mesh;
  open_mesh.plc.cap_degrees = 180;
  VolumeMeshResult r, q;
  MeshWithAndWithout(Slit(), dims, closed_mesh, open_mesh, &r, &q);
  EXPECT_EQ(r.closed_slits, 1u);
}

double SheetArea(const Plc& plc) {
  double area = 0;
  for (const Face& t : plc.sheet_triangles) {
    area += Area({plc.vertices[t[0]], plc.vertices[t[1]], plc.vertices[t[2]]});
  }
  return area;
}

TEST(PlcTest, RefiningBisectsLongestEdgesUntilTheyHalveWithoutNarrowingAnAngle) {
  // Two sheets of different pieces; the first ends on the box (x = -0.5), where its edges
  // in the box face must stay whole.
  const TriangleMesh m = Append(Square(-0.5, 12, 10, 2, 3, 2.0f), Square(4, 16, 8, 2, 5, 4.0f));
  SM_ASSERT_OK_AND_ASSIGN(Plc plc, BuildPlc(m, {20, 20, 20}, {}));
  const size_t before = plc.sheet_triangles.size();
  const double area = SheetArea(plc);
  std::vector<uint8_t> marked(before, 1);
  const Plc original = plc;
  const uint32_t split = RefineSheetTriangles(marked, &plc);
  EXPECT_GT(split, 0u);
  // Each split bisects the one or two triangles on its edge.
  EXPECT_GE(plc.sheet_triangles.size(), before + split);
  EXPECT_LE(plc.sheet_triangles.size(), before + 2 * split);
  EXPECT_EQ(plc.vertices.size(), original.vertices.size() + split);
  EXPECT_NEAR(SheetArea(plc), area, 1e-9 * area);
  // The lattice seeds are still the last vertices, where they were (MoveSeeds moves the
  // last seed_points vertices); the midpoints come before them.
  ASSERT_GT(plc.seed_points, 0u);
  const size_t seeds = plc.seed_points, first_seed = plc.vertices.size() - seeds;
  for (size_t i = 0; i < seeds; ++i) {
    EXPECT_EQ(plc.vertices[first_seed + i],
              original.vertices[original.vertices.size() - seeds + i]);
  }
  for (const Face& f : plc.sheet_triangles) {
    for (uint32_t v : f) EXPECT_LT(v, first_seed);
  }
  // One facet per sheet triangle, in order, with its marker; pieces and thicknesses kept.
  ASSERT_EQ(plc.facets.size(), 6 + plc.sheet_triangles.size());
  ASSERT_EQ(plc.sheet_piece.size(), plc.sheet_triangles.size());
  ASSERT_EQ(plc.sheet_thickness.size(), plc.sheet_triangles.size());
  for (size_t t = 0; t < plc.sheet_triangles.size(); ++t) {
    const Face& f = plc.sheet_triangles[t];
    EXPECT_EQ(plc.facets[6 + t].marker, kFirstSheetMarker + static_cast<int32_t>(t));
    EXPECT_EQ(plc.facets[6 + t].polygons, (std::vector<std::vector<uint32_t>>{{f[0], f[1], f[2]}}));
    EXPECT_EQ(plc.sheet_thickness[t], plc.sheet_piece[t] == 3 ? 2.0f : 4.0f);
  }
  // The triangles are right and isosceles and stay so (longest-edge bisection narrows no
  // angle, makes no cap); the second sheet's, off the box, have their longest edges halved
  // (6 sqrt 2 -> 3 sqrt 2); the first's that reach the box face stay whole.
  size_t whole = 0;
  for (size_t t = 0; t < plc.sheet_triangles.size(); ++t) {
    const Face& f = plc.sheet_triangles[t];
    const Vec3 p[3] = {plc.vertices[f[0]], plc.vertices[f[1]], plc.vertices[f[2]]};
    double longest = 0;
    for (int k = 0; k < 3; ++k) {
      const Vec3 u = p[(k + 1) % 3] - p[k], w = p[(k + 2) % 3] - p[k];
      const double degrees = std::acos(Dot(u, w) / (Norm(u) * Norm(w))) * 180 / std::numbers::pi;
      EXPECT_TRUE(std::abs(degrees - 45) < 1e-6 || std::abs(degrees - 90) < 1e-6) << degrees;
      longest = std::max(longest, Norm(u));
    }
    if (plc.sheet_piece[t] == 5) EXPECT_LE(longest, 3 * std::sqrt(2.0) + 1e-9);
    whole += plc.sheet_piece[t] == 3 && longest > 6.25 * std::sqrt(2.0) / 2 + 1e-9;
  }
  EXPECT_GT(whole, 0u);
  // No new vertex in the box face x = -0.5, and the box facets untouched.
  for (size_t i = original.vertices.size(); i < plc.vertices.size(); ++i) {
    EXPECT_GT(plc.vertices[i].x, -0.5 + 1e-9);
  }
  for (int f = 0; f < 6; ++f) EXPECT_EQ(plc.facets[f].polygons, original.facets[f].polygons);
  // TetGen meshes the finer PLC with every sheet triangle made of tetrahedron faces.
  TetgenOptions tetgen;
  tetgen.steiner_on_sheets = false;
  SM_ASSERT_OK_AND_ASSIGN(TetMesh mesh, RunTetgen(plc, tetgen, {}));
  EXPECT_EQ(mesh.num_sheet_faces(), plc.sheet_triangles.size());
}

TEST(PlcTest, SliversPinnedBetweenTwoSheetsAreRefinedAway) {
  // A sheet's rim running 0.8 voxels over another sheet, parallel: TetGen must fill the gap
  // under 24-voxel sheet edges, which pins flat tetrahedra (3.8 degrees). Contacts are not mended
  // here, so the gap stays; bisecting the sheet triangles around those tetrahedra raises the angle.
  const TriangleMesh m = Append(Square(2, 26, 10, 1, 0), Square(14, 38, 10.8, 1, 1));
  VolumeMeshOptions with;
  with.plc.contact_voxels = 0;
  with.plc.overlap_voxels = 0;
  VolumeMeshOptions moving = with;
  with.improve.sheet_move_voxels = 0;  // the sheets' vertices held: the refinement's work
  VolumeMeshOptions without = with;
  without.tetgen.min_dihedral_degrees = 0;  // no aim: no refinement
  VolumeMeshResult r, off;
  MeshWithAndWithout(m, {40, 40, 22}, with, without, &r, &off);
  EXPECT_EQ(off.sliver_refinement.rounds, 0u);
  EXPECT_LT(off.quality.min_dihedral.min, 10);
  EXPECT_GE(r.sliver_refinement.rounds, 1u) << r.sliver_refinement.stopped;
  EXPECT_GT(r.sliver_refinement.split_edges, 0u);
  EXPECT_GT(r.sliver_refinement.slivers_on_sheets, 0u);
  EXPECT_DOUBLE_EQ(r.sliver_refinement.min_dihedral_before, off.quality.min_dihedral.min);
  EXPECT_GT(r.sheet_faces, off.sheet_faces);
  // Not yet to 10 degrees: the worst left is not pinned at the refined triangles.
  EXPECT_GT(r.quality.min_dihedral.min, 5);
  // Where the improvement may move the sheets' vertices (by default, 1 voxel), it lifts
  // them too (8.06 degrees), if not to 10 either: the gap is a near contact, which the PLC
  // mends by default (plc.contact_voxels).
  SM_ASSERT_OK_AND_ASSIGN(const VolumeMeshResult moved,
                          BuildVolumeMesh(m, {40, 40, 22}, {}, moving));
  EXPECT_GT(moved.improvement.moved_sheet_vertices, 0u);
  // (1 voxel, and that again for each sliver round kept: each starts from the sheets as the
  // improvement left them.)
  EXPECT_LE(moved.improvement.max_sheet_move, (1 + moved.sliver_refinement.rounds) * (1 + 1e-9));
  EXPECT_GT(moved.quality.min_dihedral.min, off.quality.min_dihedral.min + 2);
  EXPECT_EQ(moved.conformity.conforming, moved.conformity.sheet_triangles);
}

TEST(PlcTest, AnEdgeAcrossACornerOfABoxFaceIsASegmentOfItsFacet) {
  // A sheet triangle whose edge a-b lies in the box face x = 19.5 with a on the box edge
  // y = 19.5 and b on the box edge z = -0.5: a chord across the face's corner, both ends on
  // its outline. TetGen crashed (unifysegments) when the chord was left out of the facet
  // as if it ran along the outline (the grazing_sheet preset, seed 1964, run r = 8).
  TriangleMesh m;
  m.vertices = {{19.5, 19.5, 5}, {19.5, 12, -0.5}, {10, 15, 5}};
  m.faces = {{0, 1, 2}};
  m.face_piece = {0};
  m.face_thickness_voxels = {1};
  SM_ASSERT_OK_AND_ASSIGN(Plc plc, BuildPlc(m, {20, 20, 20}, {}));
  const Face& t = plc.sheet_triangles.at(0);
  uint32_t a = 0, b = 0;
  for (uint32_t x : t) {
    if (Norm(plc.vertices[x] - Vec3(19.5, 19.5, 5)) < 1e-9) a = x;
    if (Norm(plc.vertices[x] - Vec3(19.5, 12, -0.5)) < 1e-9) b = x;
  }
  ASSERT_NE(a, b);
  int chords = 0;
  for (int f = 0; f < 6; ++f) {
    for (const auto& polygon : plc.facets[f].polygons) {
      chords += polygon.size() == 2 && std::min(polygon[0], polygon[1]) == std::min(a, b) &&
                std::max(polygon[0], polygon[1]) == std::max(a, b);
    }
  }
  EXPECT_EQ(chords, 1);  // in the face x = 19.5 only
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult r, BuildVolumeMesh(m, {20, 20, 20}, {}, {}));
  EXPECT_EQ(r.conformity.conforming, r.conformity.sheet_triangles);
  EXPECT_NEAR(r.quality.volume, r.box_volume, 1e-9 * r.box_volume);
}

// A PLC of sheet triangles alone, in the box [0, 20]^3 (MeasureWedges reads no facets).
Plc WedgePlc(const std::vector<Vec3>& vertices, const std::vector<Face>& triangles) {
  Plc plc;
  plc.box_lo = {0, 0, 0};
  plc.box_hi = {20, 20, 20};
  plc.vertices = vertices;
  plc.sheet_triangles = triangles;
  return plc;
}

TEST(PlcTest, TheNarrowestWedgeIsTheAngleFacetsMeetAtInAnEdge) {
  const double deg = std::numbers::pi / 180;
  // Two sheets meeting in the edge (5,5,10)-(5,15,10) at 5 degrees.
  const Vec3 a(5, 5, 10), b(5, 15, 10);
  const Vec3 c(15, 10, 10), d(5 + 10 * std::cos(5 * deg), 10, 10 + 10 * std::sin(5 * deg));
  WedgeBound w = MeasureWedges(WedgePlc({a, b, c, d}, {{0, 1, 2}, {0, 1, 3}}), 10);
  EXPECT_NEAR(w.narrowest_degrees, 5, 1e-9);
  EXPECT_EQ(w.narrow_edges, 1u);
  // One flat sheet: its inner edge has 180 degrees on either side; its rim edges none.
  w = MeasureWedges(WedgePlc({a, b, c, Vec3(1, 10, 10)}, {{0, 1, 2}, {1, 0, 3}}), 10);
  EXPECT_NEAR(w.narrowest_degrees, 180, 1e-9);
  EXPECT_EQ(w.narrow_edges, 0u);
  // A sheet leaving the box face z = 0 along its edge at 8 degrees (the wedge inside the
  // box is 8, the other side 172), and one leaving it upright (90 on both sides).
  const Vec3 f(5, 5, 0), g(5, 15, 0);
  w = MeasureWedges(
      WedgePlc({f, g, Vec3(5 + 10 * std::cos(8 * deg), 10, 10 * std::sin(8 * deg))}, {{0, 1, 2}}),
      10);
  EXPECT_NEAR(w.narrowest_degrees, 8, 1e-9);
  EXPECT_EQ(w.narrow_edges, 1u);
  w = MeasureWedges(WedgePlc({f, g, Vec3(5, 10, 10)}, {{0, 1, 2}}), 10);
  EXPECT_NEAR(w.narrowest_degrees, 90, 1e-9);
  EXPECT_EQ(w.narrow_edges, 0u);
  // No edge shared: no bound.
  w = MeasureWedges(WedgePlc({a, b, c}, {{0, 1, 2}}), 10);
  EXPECT_EQ(w.narrowest_degrees, 360);
}

}  // namespace
}  // namespace sheetmesh

namespace sheetmesh {
namespace {

// A body (the cube [8, 13]^3, piece 5) pierced by one large sheet triangle (piece 0), with
// untangling off: the repair removes the sheet's triangle, larger though it is, and keeps
// every wall of the body (without one, its region would leak into the rock). Without the
// body the same pair loses its smaller triangle.
TEST(PlcTest, RepairSparesABodysWalls) {
  TriangleMesh m = testing::Cube(8, 13, 5);
  // The sheet triangle, in the plane z = 10.3 across the cube: area 200.
  m.vertices.insert(m.vertices.end(), {{0, 0, 10.3}, {20, 0, 10.3}, {0, 20, 10.3}});
  m.faces.push_back({8, 9, 10});
  m.face_piece.push_back(0);
  m.face_thickness_voxels.push_back(2.f);
  PlcOptions o;
  o.untangle_voxels = 0;
  o.contact_voxels = 0;
  o.wedge_degrees = 0;
  o.short_edge_voxels = 0;
  o.flip_fold_degrees = 0;
  o.lattice = 0;
  o.long_edge_factor = 0;
  m.body_pieces = {5};
  SM_ASSERT_OK_AND_ASSIGN(Plc with_body, BuildPlc(m, {24, 24, 24}, {}, o));
  EXPECT_GE(with_body.repaired_triangles, 1u);
  int walls = 0, sheet = 0;
  for (int32_t p : with_body.sheet_piece) (p == 5 ? walls : sheet) += 1;
  EXPECT_EQ(walls, 12);
  EXPECT_EQ(sheet, 0);
  m.body_pieces.clear();
  SM_ASSERT_OK_AND_ASSIGN(Plc without, BuildPlc(m, {24, 24, 24}, {}, o));
  walls = sheet = 0;
  for (int32_t p : without.sheet_piece) (p == 5 ? walls : sheet) += 1;
  EXPECT_LT(walls, 12);
  EXPECT_EQ(sheet, 1);
}

}  // namespace
}  // namespace sheetmesh
