// A junction line that zig-zags is straightened in the PLC (its corner triangle goes, the
// faces it lay over are split), and a narrow wedge between two faces on an edge is opened
// by turning a far corner about the edge: known answers in the angles the sheets meet at.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "common/status_macros.h"
#include "tests/testing/status_matchers.h"
#include "tests/worker/pipeline/tet/tet_test_shapes.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/plc.h"
#include "worker/pipeline/tet/plc_parts.h"
#include "worker/pipeline/tet/volume_mesher.h"

namespace sheetmesh {
namespace {

constexpr double kDeg = std::numbers::pi / 180;

// Two sheets crossing at right angles along the line y = z = 15, x from 4 to 20: sheet A
// (piece 0) in the plane z = 15, sheet B (piece 1) in y = 15, each half 6 voxels wide, the
// junction's vertices J0..J4 every 4 voxels. With `zig_zag`, J2 lies 1 voxel into A's half
// y > 15 and 0.05 over it, and a flap (J1, J2, J3) hangs from the junction's two links
// there, folded onto A's other half, as a dual surface leaves a junction (the 192^3
// phantom's four sheets at r = 4: a flap at 1.06 degrees to a sheet).
TriangleMesh Crossing(bool zig_zag) {
  TriangleMesh m;
  auto add = [&](const Vec3& p) {
    m.vertices.push_back(p);
    return static_cast<uint32_t>(m.vertices.size() - 1);
  };
  auto face = [&](uint32_t a, uint32_t b, uint32_t c, int32_t piece) {
    m.faces.push_back({a, b, c});
    m.face_piece.push_back(piece);
    m.face_thickness_voxels.push_back(3);
  };
  std::vector<uint32_t> j;
  for (int k = 0; k < 5; ++k) {
    Vec3 p(4 + 4 * k, 15, 15);
    if (zig_zag && k == 2) p = Vec3(12, 16, 15.05);
    j.push_back(add(p));
  }
  const Vec3 halves[4] = {{0, 6, 0}, {0, -6, 0}, {0, 0, 6}, {0, 0, -6}};
  for (int h = 0; h < 4; ++h) {
    const int32_t piece = h < 2 ? 0 : 1;
    std::vector<uint32_t> far;
    for (int k = 0; k < 5; ++k) far.push_back(add(Vec3(4 + 4 * k, 15, 15) + halves[h]));
    for (int k = 0; k < 4; ++k) {
      face(j[k], j[k + 1], far[k + 1], piece);
      face(j[k], far[k + 1], far[k], piece);
    }
  }
  if (zig_zag) face(j[1], j[2], j[3], 1);
  return m;
}

TEST(PlcJunctionsTest, AZigZagJunctionIsStraightenedToTheAngleTheSheetsCrossAt) {
  const Dims dims{30, 30, 30};
  SM_ASSERT_OK_AND_ASSIGN(Plc straight, BuildPlc(Crossing(false), dims, {}, {}));
  EXPECT_EQ(straight.straightened_junctions, 0u);
  EXPECT_NEAR(MeasureWedges(straight, 10).narrowest_degrees, 90, 1e-6);

  PlcOptions off;
  off.junction_voxels = 0;
  SM_ASSERT_OK_AND_ASSIGN(Plc kept, BuildPlc(Crossing(true), dims, {}, off));
  EXPECT_EQ(kept.straightened_junctions, 0u);
  EXPECT_LT(MeasureWedges(kept, 10).narrowest_degrees, 80);

  SM_ASSERT_OK_AND_ASSIGN(Plc plc, BuildPlc(Crossing(true), dims, {}, {}));
  EXPECT_EQ(plc.straightened_junctions, 1u);
  EXPECT_NEAR(MeasureWedges(plc, 10).narrowest_degrees, 90, 1e-6);
  // J2 is on the line between J1 and J3 and the flap gone: the straight crossing.
  bool on_line = false;
  for (const Vec3& p : plc.vertices) on_line |= Norm(p - Vec3(12, 15, 15)) < 1e-9;
  EXPECT_TRUE(on_line);
  EXPECT_EQ(plc.sheet_triangles.size(), straight.sheet_triangles.size());
  auto area = [](const Plc& p) {
    double sum = 0;
    for (const Face& t : p.sheet_triangles) {
      sum += Area({p.vertices[t[0]], p.vertices[t[1]], p.vertices[t[2]]});
    }
    return sum;
  };
  EXPECT_NEAR(area(plc), area(straight), 1e-6);

  // Too far to move: left as it was.
  PlcOptions near;
  near.junction_voxels = 0.5;
  SM_ASSERT_OK_AND_ASSIGN(Plc held, BuildPlc(Crossing(true), dims, {}, near));
  EXPECT_EQ(held.straightened_junctions, 0u);
}

TEST(PlcJunctionsTest, TheVolumeMeshOfAStraightenedJunctionIsNotPinnedByTheZigZag) {
  const Dims dims{30, 30, 30};
  VolumeMeshOptions off;
  off.plc.junction_voxels = 0;
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult kept, BuildVolumeMesh(Crossing(true), dims, {}, off));
  EXPECT_LT(kept.wedges.narrowest_degrees, 80);
  EXPECT_LE(kept.quality.min_dihedral.min, kept.wedges.narrowest_degrees + 1e-6);
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult mesh, BuildVolumeMesh(Crossing(true), dims, {}, {}));
  EXPECT_GT(mesh.wedges.narrowest_degrees, 89);
  EXPECT_GE(mesh.quality.min_dihedral.min, 10);
}

// Sheet A, 40 x 40 in the plane z = 15 (edges 5), and sheet B branching off it along its
// line y = 15 at `degrees`, 24 voxels wide (rows of 4): a T-junction whose stem leans onto
// the top, its far rim 2.1 voxels over A at 5 degrees.
TriangleMesh NarrowT(double degrees) {
  TriangleMesh b;
  const Vec3 out(0, std::cos(degrees * kDeg), std::sin(degrees * kDeg));
  for (int row = 0; row <= 6; ++row) {
    for (int col = 0; col <= 8; ++col)
      b.vertices.push_back(Vec3(5 + 5 * col, 15, 15) + out * (4 * row));
  }
  for (uint32_t row = 0; row < 6; ++row) {
    for (uint32_t col = 0; col < 8; ++col) {
      const uint32_t v = row * 9 + col;
      b.faces.push_back({v, v + 1, v + 10});
      b.faces.push_back({v, v + 10, v + 9});
    }
  }
  b.face_piece.assign(b.faces.size(), 1);
  b.face_thickness_voxels.assign(b.faces.size(), 3);
  return testing::Append(testing::Square(5, 45, 15, 8, 0), b);
}

TEST(PlcJunctionsTest, ASheetBranchingOffAnotherAtFiveDegreesIsMeshedAtTenOrMore) {
  const Dims dims{50, 50, 50};
  // Held as the surface made it (no turn, no move of sheet vertices by the improvement):
  // the junction's 5 degrees bound every tetrahedron there, and the report warns.
  VolumeMeshOptions held;
  held.plc.junction_voxels = 0;
  held.plc.wedge_degrees = 0;
  held.improve.sheet_move_voxels = 0;
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult kept, BuildVolumeMesh(NarrowT(5), dims, {}, held));
  EXPECT_NEAR(kept.wedges.narrowest_degrees, 5, 1e-6);
  EXPECT_LE(kept.quality.min_dihedral.min, 5 + 1e-6);
  ASSERT_TRUE(kept.angle_warning.has_value());
  EXPECT_LE(kept.angle_warning->degrees, 5 + 1e-6);
  // By default the stem's first row turns off the top to plc.wedge_degrees (each corner
  // 4 voxels out moves 0.49 voxel), and the mesh has no angle under 10 degrees.
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult mesh, BuildVolumeMesh(NarrowT(5), dims, {}, {}));
  EXPECT_GT(mesh.opened_dihedral_wedges, 0u);
  EXPECT_GE(mesh.wedges.narrowest_degrees, 10);
  EXPECT_GE(mesh.quality.min_dihedral.min, 10);
  EXPECT_FALSE(mesh.angle_warning.has_value());
  EXPECT_EQ(mesh.conformity.conforming, mesh.conformity.sheet_triangles);
}

// Faces on the edge a-b: two pairs, each two faces at `degrees` to each other, the pairs
// opposite (two sheets crossing at that angle along the edge), in a SheetTriangles.
void TwoSheetsAt(double degrees, SheetTriangles* st, std::vector<Vec3>* v) {
  const double t = std::tan(degrees * kDeg);
  *v = {{10, 10, 10},         {14, 10, 10}, {12, 14, 10},
        {12, 14, 10 + 4 * t}, {12, 6, 10},  {12, 6, 10 - 4 * t}};
  st->faces = {{0, 1, 2}, {1, 0, 3}, {1, 0, 4}, {0, 1, 5}};
  st->piece = {0, 1, 0, 1};
  st->source = {0, 1, 2, 3};
  st->thickness.assign(4, 3);
}

// The narrowest angle between two of the faces on edge 0-1.
double NarrowestOnTheEdge(const SheetTriangles& st, const std::vector<Vec3>& v) {
  Plc plc;
  plc.box_lo = {0, 0, 0};
  plc.box_hi = {30, 30, 30};
  plc.vertices = v;
  plc.sheet_triangles = st.faces;
  return MeasureWedges(plc, 10).narrowest_degrees;
}

TEST(PlcJunctionsTest, SheetsCrossingAtSixDegreesAreTurnedApartToTheAim) {
  SheetTriangles st;
  std::vector<Vec3> v;
  TwoSheetsAt(6, &st, &v);
  ASSERT_NEAR(NarrowestOnTheEdge(st, v), 6, 1e-9);
  const std::vector<uint8_t> on_face(v.size(), 0);
  // Opening 6 to 12 degrees moves a corner 4 voxels out by about 0.42 voxel.
  std::vector<Vec3> held = v;
  EXPECT_EQ(OpenDihedralWedges(st, held, on_face, 12, 0.3), 0u);
  EXPECT_EQ(held, v);
  EXPECT_EQ(OpenDihedralWedges(st, v, on_face, 12, 2), 2u);
  EXPECT_NEAR(NarrowestOnTheEdge(st, v), 12, 1e-6);
  // The edge's ends stay; the moved corners stay as far from the edge's line.
  EXPECT_EQ(v[0], Vec3(10, 10, 10));
  EXPECT_EQ(v[1], Vec3(14, 10, 10));
  const double t = std::tan(6 * kDeg);
  for (int x : {2, 3, 4, 5}) {
    const Vec3 r = v[x] - Vec3(12, 10, 10);
    EXPECT_NEAR(std::hypot(r.y, r.z), (x == 2 || x == 4) ? 4 : 4 * std::hypot(1, t), 1e-9);
  }
  // Sheets at 20 degrees, over the aim: nothing moves.
  TwoSheetsAt(20, &st, &v);
  const std::vector<Vec3> before = v;
  EXPECT_EQ(OpenDihedralWedges(st, v, on_face, 12, 2), 0u);
  EXPECT_EQ(v, before);
}

TEST(PlcJunctionsTest, AVertexOnTheBoxIsNotTurned) {
  SheetTriangles st;
  std::vector<Vec3> v;
  TwoSheetsAt(6, &st, &v);
  const std::vector<Vec3> before = v;
  const std::vector<uint8_t> on_face = {0, 0, 1, 1, 1, 1};
  EXPECT_EQ(OpenDihedralWedges(st, v, on_face, 12, 2), 0u);
  EXPECT_EQ(v, before);
}

}  // namespace
}  // namespace sheetmesh
