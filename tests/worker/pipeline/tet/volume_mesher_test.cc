#include "worker/pipeline/tet/volume_mesher.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>

#include "tests/testing/status_matchers.h"
#include "tests/testing/temp_dir.h"
#include "common/file_util.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/tetgen_runner.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::StatusIs;
using ::sheetmesh::testing::TempDir;
using ::testing::HasSubstr;

// A square sheet of n x n quads at height z, spanning [a, b] in x and y (voxel coordinates).
TriangleMesh Square(double a, double b, double z, int n, int32_t piece = 0, float thick = 3,
                    int axis = 2) {
  TriangleMesh m;
  auto put = [&](double u, double v) {
    Vec3 p;
    p[axis] = z;
    p[(axis + 1) % 3] = u;
    p[(axis + 2) % 3] = v;
    m.vertices.push_back(p);
  };
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) put(a + (b - a) * i / n, a + (b - a) * j / n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t v = j * (n + 1) + i;
      m.faces.push_back({v, v + 1, v + n + 2});
      m.faces.push_back({v, v + n + 2, v + n + 1});
    }
  m.face_piece.assign(m.faces.size(), piece);
  m.face_thickness.assign(m.faces.size(), thick);
  return m;
}

TriangleMesh Append(TriangleMesh a, const TriangleMesh& b) {
  const uint32_t off = static_cast<uint32_t>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (Face f : b.faces) a.faces.push_back({f[0] + off, f[1] + off, f[2] + off});
  a.face_piece.insert(a.face_piece.end(), b.face_piece.begin(), b.face_piece.end());
  a.face_thickness.insert(a.face_thickness.end(), b.face_thickness.begin(), b.face_thickness.end());
  return a;
}

// The distance from p to the PLC's nearest sheet triangle.
double DistanceToSheets(const Plc& plc, const Vec3& p) {
  double d2 = 1e300;
  for (const Face& t : plc.sheet_triangles) {
    d2 = std::min(d2, PointTriangleDistance2(
                          p, {plc.vertices[t[0]], plc.vertices[t[1]], plc.vertices[t[2]]}));
  }
  return std::sqrt(d2);
}

// The smallest distance between two of `pts`.
double ClosestPair(const std::vector<Vec3>& pts) {
  double best = 1e300;
  for (size_t i = 0; i < pts.size(); ++i)
    for (size_t j = i + 1; j < pts.size(); ++j) best = std::min(best, Norm(pts[i] - pts[j]));
  return best;
}
TEST(VolumeMesherTest, BoxWithAnInternalSquareSheet) {
  Placement pl;
  pl.spacing = {0.5, 0.5, 0.5};
  pl.origin = {1, 2, 3};
  VolumeMeshOptions o;
  o.tetgen.min_dihedral_degrees = 12;
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult r,
                          BuildVolumeMesh(Square(4, 15, 10, 4), {20, 20, 20}, pl, o));
  // The tetrahedra fill the box exactly.
  EXPECT_NEAR(r.quality.volume, r.box_volume, 1e-9 * r.box_volume);
  EXPECT_DOUBLE_EQ(r.box_volume, 10.0 * 10 * 10);
  EXPECT_EQ(r.quality.inverted, 0u);
  // Every sheet triangle is the union of tagged faces of the mesh.
  EXPECT_EQ(r.conformity.sheet_triangles, 32u);
  EXPECT_EQ(r.conformity.conforming, 32u);
  EXPECT_GE(r.mesh.num_sheet_faces(), 32u);
  for (size_t f = 0; f < r.mesh.faces.size(); ++f) {
    if (r.mesh.face_marker[f] < kFirstSheetMarker) continue;
    EXPECT_EQ(r.mesh.face_piece[f], 0);
    EXPECT_FLOAT_EQ(r.mesh.face_thickness[f], 3.0f);
    EXPECT_NEAR(r.mesh.nodes[r.mesh.faces[f][0]].z, 3 + 10 * 0.5, 1e-12);
  }
  // The angle asked for holds.
  EXPECT_GE(r.quality.min_dihedral.min, 12.0 - 1e-6);
  EXPECT_GT(r.quality.min_dihedral.mean, 40.0);
}

TEST(VolumeMesherTest, ByDefaultEachSheetTriangleStaysOneFaceAndTheBoxIsSeeded) {
  // TetGen adds no point on a facet (-Y), so the box faces carry seeded points.
  const TriangleMesh sheet = Square(10, 30, 20, 4);  // edges 5 voxels, in a 40^3 box
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult r, BuildVolumeMesh(sheet, {40, 40, 40}, {}, {}));
  EXPECT_EQ(r.mesh.num_sheet_faces(), 32u);
  EXPECT_EQ(r.conformity.conforming, 32u);
  EXPECT_EQ(r.conformity.orphan_faces, 0u);
  EXPECT_NEAR(r.quality.volume, r.box_volume, 1e-9 * r.box_volume);
  EXPECT_GT(r.box_points, 0u);
  EXPECT_GT(r.seed_points, 0u);
  // Every box point is a node, and the box faces are triangulated on the box points and
  // nothing else: by Euler's formula, a face with b points on its outline and i inside has
  // 2i + b - 2 triangles, which over the 6 faces sums to 2 x (box points) + 12.
  EXPECT_GE(r.mesh.nodes.size(), 8u + 25u + r.box_points + r.seed_points);
  EXPECT_EQ(r.mesh.faces.size() - r.mesh.num_sheet_faces(), 12u + 2u * r.box_points);
  // The angle asked of TetGen (10 degrees) holds, and the mean is well above TetGen's ~40
  // (measured 54.0 degrees, radius aspect 0.85).
  EXPECT_GE(r.quality.min_dihedral.min, 10.0 - 1e-6);
  EXPECT_GT(r.quality.min_dihedral.mean, 50.0);
  EXPECT_GT(r.quality.radius_aspect.mean, 0.82);
  // With TetGen free to split facets, it does split the sheet triangles.
  VolumeMeshOptions free;
  free.tetgen.steiner_on_sheets = true;
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult s, BuildVolumeMesh(sheet, {40, 40, 40}, {}, free));
  EXPECT_EQ(s.box_points, 0u);
  EXPECT_GT(s.mesh.num_sheet_faces(), 32u);
  EXPECT_EQ(s.conformity.conforming, 32u);
}

// The 36 sheet triangles (24 vertices, voxel coordinates) around the worst tetrahedron
// of the 192^3 phantom's volume mesh at r = 7, moved into a 56^3 box: where sheets meet,
// two triangular gaps framed by sheet edges lie nearly in one plane, and with every
// sheet triangle kept whole (-Y) the sliver between them has all four corners on sheets.
TriangleMesh PhantomJunction() {
  TriangleMesh m;
  m.vertices = {
      {38.5717, 44.8649, 25.0522}, {32.3411, 32.1136, 23.0660}, {29.7590, 37.6313, 28.5249},
      {30.1685, 35.4181, 15.9297}, {26.2623, 45.1684, 20.2036}, {40.8566, 31.0954, 20.0773},
      {28.6724, 28.9082, 9.5122},  {33.0913, 19.3873, 18.4013}, {28.7829, 21.9877, 25.5706},
      {31.8115, 17.9860, 26.5811}, {20.9569, 20.1665, 34.8380}, {32.8349, 48.4435, 37.5914},
      {34.3266, 23.1402, 30.9897}, {33.5967, 26.5864, 22.2899}, {16.3610, 35.1879, 35.4050},
      {24.3535, 40.2620, 26.3535}, {37.0706, 10.9787, 39.8335}, {33.2900, 20.5300, 33.3100},
      {43.4162, 20.6744, 15.2814}, {19.9873, 45.5016, 39.9714}, {34.5279, 35.2977, 42.8106},
      {24.3085, 16.7557, 27.5591}, {38.7093, 26.8192, 30.9065}, {19.2381, 40.5702, 41.1843}};
  m.faces = {{1, 2, 3},   {1, 3, 5},    {1, 6, 3},    {7, 8, 9},   {1, 2, 5},   {2, 3, 0},
             {10, 12, 8}, {1, 5, 13},   {7, 13, 8},   {14, 2, 1},  {1, 13, 2},  {2, 14, 15},
             {2, 4, 0},   {2, 4, 3},    {7, 6, 13},   {2, 15, 4},  {6, 5, 13},  {12, 16, 17},
             {12, 8, 13}, {2, 0, 5},    {2, 19, 0},   {2, 8, 12},  {2, 13, 8},  {10, 2, 12},
             {14, 19, 2}, {12, 17, 9},  {12, 9, 8},   {13, 5, 18}, {7, 13, 18}, {14, 1, 10},
             {10, 8, 21}, {16, 12, 22}, {13, 22, 12}, {11, 2, 23}, {20, 2, 11}, {2, 20, 23}};
  m.face_piece.assign(m.faces.size(), 0);
  m.face_thickness.assign(m.faces.size(), 2.f);
  return m;
}

TEST(VolumeMesherTest, ASliverPinnedBySheetsSplitsASheetFaceOrEdgeAndTheSheetsStillTile) {
  const TriangleMesh sheets = PhantomJunction();
  const Dims dims{56, 56, 56};
  // The PLC's wedge opening (tested on its own) would move the sheets here; kept still,
  // the splits are what mends the sliver.
  VolumeMeshOptions split;
  split.plc.wedge_degrees = 0;
  VolumeMeshOptions whole = split;
  whole.improve.split_sheets_below_degrees = 0;
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult a, BuildVolumeMesh(sheets, dims, {}, whole));
  // Kept whole, each sheet triangle is one face and the sliver stays (2.88 degrees).
  EXPECT_EQ(a.mesh.num_sheet_faces(), a.conformity.sheet_triangles);
  EXPECT_EQ(a.improvement.sheet_face_splits + a.improvement.sheet_edge_splits, 0u);
  EXPECT_LT(a.quality.min_dihedral.min, 5.0);
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult b, BuildVolumeMesh(sheets, dims, {}, split));
  // By default a vertex on a sheet edge or face next to it mends it (10.6 degrees).
  EXPECT_GT(b.improvement.sheet_face_splits + b.improvement.sheet_edge_splits, 0u);
  EXPECT_GT(b.mesh.num_sheet_faces(), b.conformity.sheet_triangles);
  EXPECT_GE(b.quality.min_dihedral.min, 10.0);
  EXPECT_GT(b.quality.min_dihedral.mean, 48.0);
  // Still conforming: every input triangle is exactly tiled by faces on it, carrying its
  // piece and thickness; nothing inverted, the box filled.
  EXPECT_EQ(b.conformity.conforming, b.conformity.sheet_triangles);
  EXPECT_EQ(b.conformity.orphan_faces, 0u);
  EXPECT_LT(b.conformity.worst_area_error, 1e-9);
  EXPECT_EQ(b.quality.inverted, 0u);
  EXPECT_NEAR(b.quality.volume, b.box_volume, 1e-9 * b.box_volume);
  // The sheet faces cover what the whole triangles did (the PLC's, after its flips).
  auto sheet_area = [](const TetMesh& mesh) {
    double area = 0;
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      if (mesh.face_piece[f] < 0) continue;
      EXPECT_EQ(mesh.face_piece[f], 0);
      EXPECT_EQ(mesh.face_thickness[f], 2.f);
      const auto& x = mesh.faces[f];
      area += Area({mesh.nodes[x[0]], mesh.nodes[x[1]], mesh.nodes[x[2]]});
    }
    return area;
  };
  EXPECT_NEAR(sheet_area(b.mesh), sheet_area(a.mesh), 1e-9 * sheet_area(a.mesh));
}

TEST(VolumeMesherTest, WithoutSheetsTheBoxIsStillFilled) {
  // No sheet, so no length scale to seed by: no seeds, and the box is meshed as it is.
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult r,
                          BuildVolumeMesh(TriangleMesh{}, {10, 20, 30}, {}, {}));
  EXPECT_EQ(r.box_points + r.seed_points, 0u);
  EXPECT_EQ(r.mesh.num_sheet_faces(), 0u);
  EXPECT_GT(r.mesh.tets.size(), 0u);
  EXPECT_NEAR(r.quality.volume, 10.0 * 20 * 30, 1e-9 * 6000);
  EXPECT_EQ(r.quality.inverted, 0u);
}

TEST(PlcTest, BoxSeedsLieOnTheBoxInItsFacetsGradedAwayFromTheSheets) {
  // The 40 x 40 sheet of the lattice test below in a 60^3 box [-0.5, 59.5]^3, spacing 5:
  // level 0 (h = 5) lies 3 to 13 from the sheet, level 1 (h = 10) 13 to 33.
  const TriangleMesh sheet = Square(10, 50, 30, 8);
  PlcOptions o;
  o.lattice = 1.0;
  o.seed_box = true;
  SM_ASSERT_OK_AND_ASSIGN(Plc plc, BuildPlc(sheet, {60, 60, 60}, {}, o));
  ASSERT_GT(plc.box_points, 0u);
  const uint32_t first = 8 + 81, end = first + plc.box_points;
  ASSERT_EQ(plc.vertices.size(), end + plc.seed_points);
  auto faces_of = [](const Vec3& p) {
    int bits = 0;
    for (int k = 0; k < 3; ++k) {
      if (std::abs(p[k] + 0.5) < 1e-12) bits |= 1 << (2 * k);
      if (std::abs(p[k] - 59.5) < 1e-12) bits |= 1 << (2 * k + 1);
    }
    return bits;
  };
  // Each box point is on the box, in the facet of each face it lies on, and nowhere else:
  // points inside a face as a point of its facet, points on an edge in both faces' outlines.
  std::vector<int> seen(plc.vertices.size(), 0);
  for (size_t f = 0; f < plc.facets.size(); ++f) {
    for (const auto& poly : plc.facets[f].polygons) {
      for (uint32_t v : poly) {
        if (v < first || v >= end) continue;
        ASSERT_LT(f, 6u) << "box point " << v << " on a sheet facet";
        EXPECT_TRUE(faces_of(plc.vertices[v]) & (1 << f)) << "box point " << v << " facet " << f;
        EXPECT_EQ(poly.size() == 1,
                  std::popcount(static_cast<unsigned>(faces_of(plc.vertices[v]))) == 1);
        seen[v] |= 1 << f;
      }
    }
  }
  std::vector<Vec3> near;
  for (uint32_t v = first; v < end; ++v) {
    const Vec3& p = plc.vertices[v];
    const int bits = faces_of(p);
    ASSERT_NE(bits, 0) << "box point " << v << " off the box";
    EXPECT_EQ(seen[v], bits) << "box point " << v;
    // 3 off the box's corners and edges of its own level, and off the sheet.
    const double d = DistanceToSheets(plc, p);
    EXPECT_GT(d, 3.0 - 1e-9);
    if (d < 13.0) near.push_back(p);
  }
  // Each outline runs once round its face, in order: its length is the face's perimeter.
  for (int f = 0; f < 6; ++f) {
    const auto& outline = plc.facets[f].polygons[0];
    double length = 0;
    for (size_t i = 0; i < outline.size(); ++i) {
      length += Norm(plc.vertices[outline[(i + 1) % outline.size()]] - plc.vertices[outline[i]]);
    }
    EXPECT_NEAR(length, 4 * 60.0, 1e-9) << "face " << f;
  }
  // Level 0 points are 5 apart along rows and edges.
  ASSERT_GT(near.size(), 1u);
  EXPECT_NEAR(ClosestPair(near), 5.0, 1e-9);
  // Not seeded unless asked.
  o.seed_box = false;
  SM_ASSERT_OK_AND_ASSIGN(Plc plain, BuildPlc(sheet, {60, 60, 60}, {}, o));
  EXPECT_EQ(plain.box_points, 0u);
}

TEST(VolumeMesherTest, CrossingSheetsMeetingAlongAnEdge) {
  // Two sheets crossing along the line y = 10, z = 10: the horizontal one is split along the
  // line so that both share its edges.
  TriangleMesh horizontal;
  {
    TriangleMesh left = Square(4, 10, 10, 3), right = Square(10, 16, 10, 3);
    // Squares span [a, b] in both x and y; keep x over [4, 16] by building two halves in y.
    horizontal = Append(left, right);
  }
  TriangleMesh vertical = Square(4, 16, 10, 6, /*piece=*/1, 2, /*axis=*/1);  // plane y = 10
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult r,
                          BuildVolumeMesh(Append(horizontal, vertical), {20, 20, 20}, {}, {}));
  EXPECT_EQ(r.conformity.conforming, r.conformity.sheet_triangles);
  std::set<int32_t> pieces;
  for (int32_t p : r.mesh.face_piece) pieces.insert(p);
  EXPECT_EQ(pieces, (std::set<int32_t>{-1, 0, 1}));
  EXPECT_NEAR(r.quality.volume, r.box_volume, 1e-9 * r.box_volume);
}

TEST(VolumeMesherTest, SheetsReachingTheBoxEndOnIt) {
  // A sheet from wall to wall: its rim vertices sit on the outermost voxel centres and snap
  // onto the box faces.
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult r,
                          BuildVolumeMesh(Square(0, 19, 10, 5), {20, 20, 20}, {}, {}));
  EXPECT_GT(r.snapped_vertices, 0u);
  EXPECT_EQ(r.conformity.conforming, r.conformity.sheet_triangles);
  EXPECT_NEAR(r.quality.volume, r.box_volume, 1e-9 * r.box_volume);
}

TEST(VolumeMesherTest, ASheetEndingAVoxelShortOfTheBoxSnapsOntoItUnlessThatMakesAClash) {
  // The square's rim lies 1 voxel inside the x and y faces of the box: beyond snap_voxels
  // (0.75), within snap_clear_voxels (1.5).
  const TriangleMesh square = Square(0.5, 18.5, 10, 5);
  auto on_box = [](const Plc& plc) {
    uint32_t n = 0;
    for (uint32_t i = 8; i < plc.vertices.size(); ++i) {
      const Vec3& p = plc.vertices[i];
      n += p.x == -0.5 || p.x == 19.5 || p.y == -0.5 || p.y == 19.5;
    }
    return n;
  };
  PlcOptions near_only;
  near_only.snap_clear_voxels = 0;
  near_only.seed_box = false;
  PlcOptions wide = near_only;
  wide.snap_clear_voxels = 1.5;
  SM_ASSERT_OK_AND_ASSIGN(const Plc a, BuildPlc(square, {20, 20, 20}, {}, near_only));
  SM_ASSERT_OK_AND_ASSIGN(const Plc b, BuildPlc(square, {20, 20, 20}, {}, wide));
  EXPECT_EQ(a.snapped_vertices, 0u);
  EXPECT_EQ(on_box(a), 0u);
  EXPECT_EQ(b.snapped_vertices, 20u);  // the 5 x 4 rim vertices
  EXPECT_EQ(on_box(b), 20u);
  EXPECT_EQ(b.snap_held_vertices, 0u);
  EXPECT_EQ(PlcOptions().snap_clear_voxels, 1.5);
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult r, BuildVolumeMesh(square, {20, 20, 20}, {}, {}));
  EXPECT_EQ(r.snapped_vertices, 20u);
  EXPECT_EQ(r.conformity.conforming, r.conformity.sheet_triangles);
  EXPECT_GE(r.quality.min_dihedral.min, 10.0 - 1e-6);

  // Triangle A (in the plane y = 10) has its corner P 1 voxel off the face x = -0.5;
  // triangle B's two corners 0.6 off that face always snap. Snapped, P would swing A
  // through B (in the plane y = 10, B runs from (-0.5, z 9.8) up to (2, z 11.4), above A's
  // edge P-R but below where that edge goes once P is at x = -0.5), so P stays.
  TriangleMesh clash;
  clash.vertices = {{0.5, 10, 10}, {4, 10, 7},     {4, 10, 13},     // A: P, Q, R
                    {0.1, 9, 9.8}, {0.1, 11, 9.8}, {2, 10, 11.4}};  // B
  clash.faces = {{0, 1, 2}, {3, 4, 5}};
  clash.face_piece = {0, 1};
  clash.face_thickness = {1, 1};
  const Dims dims{16, 20, 20};
  SM_ASSERT_OK_AND_ASSIGN(const Plc held, BuildPlc(clash, dims, {}, wide));
  EXPECT_EQ(held.snap_held_vertices, 1u);
  EXPECT_EQ(held.snapped_vertices, 2u);  // B's two
  EXPECT_EQ(held.sheet_triangles.size(), 2u);
  auto has = [](const Plc& plc, const Vec3& q) {
    return std::any_of(plc.vertices.begin(), plc.vertices.end(),
                       [&](const Vec3& p) { return Norm(p - q) < 1e-12; });
  };
  EXPECT_TRUE(has(held, {0.5, 10, 10}));
  EXPECT_TRUE(has(held, {-0.5, 9, 9.8}));
  // Snapping P regardless makes the clash, which the check reports.
  PlcOptions forced = near_only;
  forced.snap_voxels = 1.5;
  EXPECT_THAT(BuildPlc(clash, dims, {}, forced),
              StatusIs(absl::StatusCode::kFailedPrecondition, HasSubstr("intersect")));
  // Without B, P snaps.
  TriangleMesh alone = clash;
  alone.faces.pop_back();
  alone.face_piece.pop_back();
  alone.face_thickness.pop_back();
  SM_ASSERT_OK_AND_ASSIGN(const Plc free, BuildPlc(alone, dims, {}, wide));
  EXPECT_EQ(free.snap_held_vertices, 0u);
  EXPECT_TRUE(has(free, {-0.5, 10, 10}));
  // The whole volume mesh builds with P held back.
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult v, BuildVolumeMesh(clash, dims, {}, {}));
  EXPECT_EQ(v.snap_held_vertices, 1u);
  EXPECT_EQ(v.conformity.conforming, v.conformity.sheet_triangles);
}

// Two triangles of a flat quad split along its long diagonal a-b (a thin pair), with the
// fourth corner d lifted by `lift` out of the plane; pieces and thicknesses given. c lies
// `bulge` off a-b: at 1.5 its angle is ~163 degrees (a flat triangle), at 2.5 ~152.
TriangleMesh ThinPair(double lift, int32_t piece_f, int32_t piece_g, double bulge = 1.5) {
  TriangleMesh m;
  m.vertices = {{10, 10, 20}, {30, 10, 20}, {20, 10 + bulge, 20}, {20, 8.5, 20 + lift}};  // a b c d
  m.faces = {{0, 1, 2}, {1, 0, 3}};
  m.face_piece = {piece_f, piece_g};
  m.face_thickness = {2, 4};
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
  // Two pieces meeting along an edge keep it.
  SM_ASSERT_OK_AND_ASSIGN(Plc pieces, BuildPlc(ThinPair(0, 0, 1, 2.5), {40, 20, 40}, {}));
  EXPECT_EQ(pieces.flipped_edges, 0u);
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
  m.face_thickness = {3, 3};
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

TEST(PlcTest, LatticeSeedsKeepOffTheSheetsAndTheBoxAndCoarsenAway) {
  // A 40 x 40 square sheet of 8 x 8 quads (edges 5 and 7.07 voxels: median 5) in a 60^3
  // box; the lattice at 1 x the median edge has spacing 5 next to the sheet.
  const TriangleMesh sheet = Square(10, 50, 30, 8);
  PlcOptions o;
  o.lattice = 1.0;
  SM_ASSERT_OK_AND_ASSIGN(Plc plc, BuildPlc(sheet, {60, 60, 60}, {}, o));
  EXPECT_NEAR(plc.lattice_spacing, 5.0, 1e-9);
  ASSERT_GT(plc.seed_points, 0u);
  const size_t first_seed = plc.vertices.size() - plc.seed_points;
  EXPECT_EQ(first_seed, 8u + 81u);  // box corners, sheet vertices, then the seeds
  for (const PlcFacet& f : plc.facets) {
    for (const auto& poly : f.polygons) {
      for (uint32_t v : poly) EXPECT_LT(v, first_seed) << "a seed on a facet";
    }
  }
  // Seeds stay 0.6 spacings off the sheet and the box (box [-0.5, 59.5]^3); level 0 (spacing
  // 5) reaches 0.6 * 5 + 2.5 * 5 = 15.5 from the sheet, level 1 (spacing 10) fills the rest
  // (level 2's spacing, 20, is over a quarter of the box's 60).
  std::vector<Vec3> near, far;
  for (size_t i = first_seed; i < plc.vertices.size(); ++i) {
    const Vec3& p = plc.vertices[i];
    const double d = DistanceToSheets(plc, p);
    EXPECT_GT(d, 3.0 - 1e-9);
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(p[k], -0.5 + 3.0 - 1e-9);
      EXPECT_LE(p[k], 59.5 - 3.0 + 1e-9);
    }
    (d <= 15.5 ? near : far).push_back(p);
  }
  ASSERT_FALSE(near.empty());
  ASSERT_FALSE(far.empty());
  // A BCC lattice's nearest neighbours are sqrt(3)/2 spacings apart.
  EXPECT_NEAR(ClosestPair(near), std::sqrt(3.0) / 2 * 5, 1e-9);
  EXPECT_GE(ClosestPair(far), std::sqrt(3.0) / 2 * 10 - 1e-9);
  // None at 0.
  PlcOptions off;
  off.lattice = 0;
  SM_ASSERT_OK_AND_ASSIGN(Plc plain, BuildPlc(sheet, {60, 60, 60}, {}, off));
  EXPECT_EQ(plain.seed_points, 0u);
  EXPECT_EQ(plain.vertices.size(), first_seed);
}

TEST(PlcTest, AThinBoxKeepsTheLatticeAtTheSpacingsThatFitIt) {
  // The same sheet at z = 10 in a box 80 x 80 x 20 ([-0.5, 19.5] in z): level 1's spacing,
  // 10, is over a quarter of 20, so level 0 (spacing 5) fills the whole box, out to 27
  // voxels from the sheet, where the box 40 thick below has level 1's spacing 10.
  PlcOptions o;
  o.lattice = 1.0;
  // The seeds beyond level 0's band (15.5 from the sheet).
  auto far_seeds = [](const Plc& plc) {
    std::vector<Vec3> far;
    for (size_t i = plc.vertices.size() - plc.seed_points; i < plc.vertices.size(); ++i) {
      if (DistanceToSheets(plc, plc.vertices[i]) > 15.5) far.push_back(plc.vertices[i]);
    }
    return far;
  };
  SM_ASSERT_OK_AND_ASSIGN(Plc thin, BuildPlc(Square(10, 50, 10, 8), {80, 80, 20}, {}, o));
  ASSERT_GT(thin.seed_points, 0u);
  for (size_t i = thin.vertices.size() - thin.seed_points; i < thin.vertices.size(); ++i) {
    EXPECT_GE(thin.vertices[i].z, -0.5 + 3.0 - 1e-9);
    EXPECT_LE(thin.vertices[i].z, 19.5 - 3.0 + 1e-9);
  }
  std::vector<Vec3> far = far_seeds(thin);
  ASSERT_GE(far.size(), 2u);
  EXPECT_NEAR(ClosestPair(far), std::sqrt(3.0) / 2 * 5, 1e-9);
  // A box 40 thick has room for level 1 (4 x 10 = 40): coarser seeds out there.
  SM_ASSERT_OK_AND_ASSIGN(Plc thick, BuildPlc(Square(10, 50, 10, 8), {80, 80, 40}, {}, o));
  far = far_seeds(thick);
  ASSERT_GE(far.size(), 2u);
  EXPECT_GE(ClosestPair(far), std::sqrt(3.0) / 2 * 10 - 1e-9);
}

TEST(VolumeMesherTest, LatticeSeededMeshConformsFillsTheBoxAndIsBetterShaped) {
  const TriangleMesh sheet = Square(10, 30, 20, 4);  // edges 5 voxels, in a 40^3 box
  VolumeMeshOptions plain, seeded;
  plain.plc.lattice = 0;
  seeded.plc.lattice = 0.85;
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult a, BuildVolumeMesh(sheet, {40, 40, 40}, {}, plain));
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult b, BuildVolumeMesh(sheet, {40, 40, 40}, {}, seeded));
  EXPECT_EQ(a.seed_points, 0u);
  EXPECT_GT(b.seed_points, 0u);
  EXPECT_NEAR(b.lattice_spacing, 0.85 * 5, 1e-9);
  EXPECT_EQ(b.conformity.conforming, b.conformity.sheet_triangles);
  EXPECT_EQ(b.conformity.orphan_faces, 0u);
  EXPECT_NEAR(b.quality.volume, b.box_volume, 1e-9 * b.box_volume);
  EXPECT_GE(b.quality.min_dihedral.min, 10.0 - 1e-6);
  EXPECT_GE(b.mesh.nodes.size(), 8u + 25u + b.seed_points);  // every seed is a node
  // The lattice's near-ideal tetrahedra lift the means.
  EXPECT_GT(b.quality.min_dihedral.mean, a.quality.min_dihedral.mean + 1.0)
      << a.mesh.tets.size() << " vs " << b.mesh.tets.size() << " tets";
  EXPECT_GT(b.quality.radius_aspect.mean, a.quality.radius_aspect.mean);
}

TEST(PlcTest, AFragmentLyingOnASheetIsDropped) {
  // A 4 x 4 square sheet at z = 10 and a lone triangle 0.2 voxel above it, tilted by ~2
  // degrees: TetGen would fill the 0.2-voxel wedge between them with slivers.
  TriangleMesh fragment;
  fragment.vertices = {{6, 6, 10.2}, {11, 6, 10.2}, {6, 11, 10.37}};
  fragment.faces = {{0, 1, 2}};
  fragment.face_piece = {1};
  fragment.face_thickness = {2};
  const TriangleMesh m = Append(Square(4, 16, 10, 4), fragment);
  SM_ASSERT_OK_AND_ASSIGN(Plc plc, BuildPlc(m, {20, 20, 20}, {}));
  EXPECT_EQ(plc.dropped_overlaps, 1u);
  ASSERT_EQ(plc.sheet_triangles.size(), 32u);
  for (int32_t piece : plc.sheet_piece) EXPECT_EQ(piece, 0);
  // Off: kept (and TetGen meshes the wedge).
  PlcOptions keep;
  keep.overlap_voxels = 0;
  SM_ASSERT_OK_AND_ASSIGN(Plc kept, BuildPlc(m, {20, 20, 20}, {}, keep));
  EXPECT_EQ(kept.dropped_overlaps, 0u);
  EXPECT_EQ(kept.sheet_triangles.size(), 33u);
  // The volume mesh without the fragment has no sliver from it, and says what went.
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult r, BuildVolumeMesh(m, {20, 20, 20}, {}, {}));
  EXPECT_EQ(r.dropped_overlaps, 1u);
  EXPECT_EQ(r.conformity.conforming, 32u);
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult with, BuildVolumeMesh(m, {20, 20, 20}, {}, [] {
                            VolumeMeshOptions o;
                            o.plc.overlap_voxels = 0;
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
  m.face_thickness = {1, 1};
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

TEST(PlcTest, ANarrowWedgeBetweenASheetFaceAndAnEdgeOverItOpens) {
  const Dims dims{20, 20, 20};
  const Vec3 w0(11, 11, 11.5);
  const double in_plane = std::sqrt(72.0);  // |O-W| in A's plane
  PlcOptions base;
  base.lattice = 0;
  // By default W moves 1 voxel (the most it may) straight down: 10.0 degrees.
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
  blocked.face_thickness.push_back(1);
  for (const PlcOptions& o : {base, far}) {
    SM_ASSERT_OK_AND_ASSIGN(const Plc d, BuildPlc(blocked, dims, {}, o));
    EXPECT_EQ(d.opened_wedges, 0u);
    EXPECT_LT(Norm(Nearest(d, w0) - w0), 1e-12);
  }
  // The opened wedge meshes with a better worst tetrahedron (14.0 degrees, 4.8 closed).
  VolumeMeshOptions opened, closed;
  closed.plc.wedge_degrees = 0;
  VolumeMeshResult r, s;
  MeshWithAndWithout(NarrowWedge(), dims, opened, closed, &r, &s);
  EXPECT_EQ(r.opened_wedges, 1u);
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
  m.face_thickness.assign(4, 1);
  return m;
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

TEST(VolumeMesherTest, IntersectingFacetsAreReportedNotPassedOn) {
  // A vertical square piercing a horizontal one without sharing edges.
  TriangleMesh m = Append(Square(4, 15, 10, 2), Square(5, 14, 9.5, 2, 1, 3, /*axis=*/0));
  auto r = BuildVolumeMesh(m, {20, 20, 20}, {}, {});
  EXPECT_THAT(r, StatusIs(absl::StatusCode::kFailedPrecondition,
                          ::testing::AllOf(HasSubstr("intersect"), HasSubstr("triangles"))));
  VolumeMeshOptions repair;
  repair.plc.repair = true;
  auto fixed = BuildVolumeMesh(m, {20, 20, 20}, {}, repair);
  // Removing one triangle of each pair is not enough for a full piercing: still refused,
  // with the reason, and nothing is passed to TetGen.
  if (!fixed.ok()) {
    EXPECT_THAT(fixed,
                StatusIs(absl::StatusCode::kFailedPrecondition, HasSubstr("still intersect")));
  } else {
    EXPECT_GT(fixed->repaired_triangles, 0u);
  }
}

TEST(VolumeMesherTest, RepairRemovesASimpleClash) {
  // One small triangle cutting through a sheet: removing it is the whole repair.
  TriangleMesh m = Square(4, 15, 10, 2);
  const uint32_t base = static_cast<uint32_t>(m.vertices.size());
  m.vertices.push_back({8, 8, 9});
  m.vertices.push_back({9, 8, 11});
  m.vertices.push_back({8.5, 9, 11});
  m.faces.push_back({base, base + 1, base + 2});
  m.face_piece.push_back(1);
  m.face_thickness.push_back(1);
  EXPECT_THAT(BuildVolumeMesh(m, {20, 20, 20}, {}, {}),
              StatusIs(absl::StatusCode::kFailedPrecondition));
  VolumeMeshOptions o;
  o.plc.repair = true;
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult r, BuildVolumeMesh(m, {20, 20, 20}, {}, o));
  EXPECT_EQ(r.repaired_triangles, 1u);
  EXPECT_EQ(r.conformity.sheet_triangles, 8u);
}

// A stand-in TetGen: a script that behaves badly.
std::string FakeTetgen(const TempDir& tmp, const std::string& body) {
  const std::string path = tmp.File("fake-tetgen");
  EXPECT_TRUE(WriteFileAtomically(path, "#!/bin/sh\n" + body + "\n").ok());
  std::filesystem::permissions(path, std::filesystem::perms::owner_all);
  return path;
}

TEST(VolumeMesherTest, TetgenSwitchesLeaveOutTetgensOwnVertexInsertion) {
  // -O2/3: TetGen's flips and smoothing only; its vertex insertion/deletion (operation 4)
  // listed facet faces no tetrahedron had.
  // -Y by default: TetGen adds no point on a facet.
  EXPECT_EQ(TetgenSwitches({}), "-pzQq1.5/10O2/3Y");
  TetgenOptions o;
  o.max_radius_edge_ratio = 0;
  o.max_volume = 5;
  o.steiner_on_sheets = true;
  EXPECT_EQ(TetgenSwitches(o), "-pzQa5O2/3");
}

TEST(VolumeMesherTest, TetgenThatHangsIsKilledAtTheTimeLimit) {
  TempDir tmp;
  VolumeMeshOptions o;
  o.tetgen.program = FakeTetgen(tmp, "sleep 30");
  o.tetgen.time_limit_seconds = 0.5;
  EXPECT_THAT(BuildVolumeMesh(Square(4, 15, 10, 2), {20, 20, 20}, {}, o),
              StatusIs(absl::StatusCode::kDeadlineExceeded, HasSubstr("time limit of 0.5 s")));
}

TEST(VolumeMesherTest, TetgenThatIsKilledOrFailsGivesTheDocumentedErrors) {
  TempDir tmp;
  VolumeMeshOptions o;
  o.tetgen.program = FakeTetgen(tmp, "echo dying; kill -9 $$");
  EXPECT_THAT(BuildVolumeMesh(Square(4, 15, 10, 2), {20, 20, 20}, {}, o),
              StatusIs(absl::StatusCode::kInternal,
                       ::testing::AllOf(HasSubstr("signal 9"), HasSubstr("dying"))));
  o.tetgen.program = FakeTetgen(tmp, "echo 'Error: self-intersection'; exit 3");
  EXPECT_THAT(BuildVolumeMesh(Square(4, 15, 10, 2), {20, 20, 20}, {}, o),
              StatusIs(absl::StatusCode::kInternal,
                       ::testing::AllOf(HasSubstr("code 3"), HasSubstr("self-intersection"))));
  o.tetgen.program = "no-such-tetgen-program";
  EXPECT_THAT(BuildVolumeMesh(Square(4, 15, 10, 2), {20, 20, 20}, {}, o),
              StatusIs(absl::StatusCode::kNotFound));
}

TEST(VolumeMesherTest, CancellationKillsTetgen) {
  TempDir tmp;
  VolumeMeshOptions o;
  o.tetgen.program = FakeTetgen(tmp, "sleep 30");
  struct Stop : ProgressObserver {
    bool OnProgress(absl::string_view, double, absl::string_view) override { return false; }
  } stop;
  EXPECT_THAT(BuildVolumeMesh(Square(4, 15, 10, 2), {20, 20, 20}, {}, o, Progress(&stop, "volume")),
              StatusIs(absl::StatusCode::kCancelled));
}

TEST(TetQualityTest, RegularTetrahedronScoresOne) {
  const double s = 1.0 / std::sqrt(2.0);
  const TetShape q = MeasureTet({1, 0, -s}, {-1, 0, -s}, {0, 1, s}, {0, -1, s});
  EXPECT_NEAR(q.min_dihedral_degrees, 70.5288, 1e-3);
  EXPECT_NEAR(q.gamma, 1.0, 1e-9);
  EXPECT_NEAR(q.edge_aspect, 1.0, 1e-9);
  EXPECT_NEAR(q.radius_aspect, 1.0, 1e-9);
  const TetShape flat = MeasureTet({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.3, 0.3, 1e-3});
  EXPECT_LT(flat.min_dihedral_degrees, 1.0);
  EXPECT_LT(flat.radius_aspect, 0.05);
}

TEST(TetQualityTest, RadiusAspectOfTheCornerTetrahedronIsRootThreeMinusOne) {
  // r_in = 1 / (3 + sqrt 3), R = sqrt 3 / 2: 3 r_in / R = sqrt 3 - 1.
  const Vec3 o{0, 0, 0}, x{1, 0, 0}, y{0, 1, 0}, z{0, 0, 1};
  EXPECT_NEAR(RadiusAspect(o, x, y, z), std::sqrt(3.0) - 1, 1e-12);
  EXPECT_NEAR(RadiusAspect(o, y, x, z), std::sqrt(3.0) - 1, 1e-12);  // either orientation
  EXPECT_NEAR(MeasureTet(o, x, y, z).radius_aspect, std::sqrt(3.0) - 1, 1e-12);
  EXPECT_EQ(RadiusAspect(o, x, y, {2, 3, 0}), 0);  // flat
}

}  // namespace
}  // namespace sheetmesh
