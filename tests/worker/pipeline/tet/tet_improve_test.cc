#include "worker/pipeline/tet/tet_improve.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
#include <tuple>

#include "absl/container/flat_hash_set.h"
#include "tests/testing/status_matchers.h"
#include "worker/pipeline/tet/plc.h"
#include "worker/pipeline/tet/tet_contraction.h"
#include "worker/pipeline/tet/tet_mesh_editor.h"
#include "worker/pipeline/tet/vertex_freedom.h"
#include "worker/pipeline/tet/volume_mesher.h"

namespace sheetmesh {
namespace {

double Worst(const TetMesh& m) {
  double w = 1e300;
  for (const Tet& t : m.tets) {
    w = std::min(w, MinDihedralDegrees(m.nodes[t[0]], m.nodes[t[1]], m.nodes[t[2]], m.nodes[t[3]]));
  }
  return w;
}

double Volume(const TetMesh& m) {
  double v = 0;
  for (const Tet& t : m.tets)
    v += TetVolume(m.nodes[t[0]], m.nodes[t[1]], m.nodes[t[2]], m.nodes[t[3]]);
  return v;
}

TEST(TetImproveTest, MinDihedralOfARegularTetrahedronAndOfAnInvertedOne) {
  const Vec3 a{1, 1, 1}, b{1, -1, -1}, c{-1, 1, -1}, d{-1, -1, 1};
  const double q = MinDihedralDegrees(a, b, c, d) > 0 ? MinDihedralDegrees(a, b, c, d)
                                                      : MinDihedralDegrees(b, a, c, d);
  EXPECT_NEAR(q, std::acos(1.0 / 3) * 180 / M_PI, 1e-9);
  // The same tetrahedron with two vertices swapped is inverted.
  EXPECT_LT(std::min(MinDihedralDegrees(a, b, c, d), MinDihedralDegrees(b, a, c, d)), 0);
  EXPECT_LT(MinDihedralDegrees(a, b, c, (a + b + c) / 3.0), 0) << "flat";
}

// A bipyramid: the ring a, b, c around the edge u-v. Three tetrahedra around u-v, or two
// sharing the face a-b-c; the hull's faces are facet faces, so no vertex may move.
TetMesh Bipyramid() {
  TetMesh m;
  m.nodes = {{1, 0, 0},
             {-0.5, std::sqrt(0.75), 0},
             {-0.5, -std::sqrt(0.75), 0},
             {0, 0, -0.6},
             {0, 0, 0.6}};
  const uint32_t a = 0, b = 1, c = 2, u = 3, v = 4;
  m.tets = {{u, v, a, b}, {u, v, b, c}, {u, v, c, a}};
  m.faces = {{a, b, u}, {b, c, u}, {c, a, u}, {a, b, v}, {b, c, v}, {c, a, v}};
  for (size_t f = 0; f < m.faces.size(); ++f) {
    m.face_marker.push_back(kFirstSheetMarker + static_cast<int32_t>(f));
    m.face_piece.push_back(0);
    m.face_thickness_voxels.push_back(1);
  }
  return m;
}

TEST(TetImproveTest, ThreeTetrahedraAroundAnEdgeBecomeTheBetterTwo) {
  TetMesh m = Bipyramid();
  for (const Tet& t : m.tets) {
    ASSERT_GT(TetVolume(m.nodes[t[0]], m.nodes[t[1]], m.nodes[t[2]], m.nodes[t[3]]), 0);
  }
  const double volume = Volume(m), three = Worst(m);
  TetMesh two = m;
  two.tets = {{0, 1, 2, 4}, {1, 0, 2, 3}};
  ASSERT_GT(Worst(two), three + 1) << "the two-tetrahedron configuration is the better one";
  TetImproveReport report;
  ASSERT_TRUE(ImproveTetMesh(&m, {-0.5, -1, -0.6}, {1, 1, 0.6}, 5, {}, &report).ok());
  EXPECT_EQ(m.tets.size(), 2u);
  EXPECT_EQ(report.edge_removals, 1u);
  EXPECT_EQ(report.movable_vertices, 0u);
  EXPECT_NEAR(Volume(m), volume, 1e-12);
  EXPECT_NEAR(Worst(m), Worst(two), 1e-9);
  EXPECT_NEAR(report.min_dihedral_before, three, 1e-9);
  EXPECT_NEAR(report.min_dihedral_after, Worst(two), 1e-9);
  for (const Tet& t : m.tets) {
    const std::set<uint32_t> s(t.begin(), t.end());
    EXPECT_TRUE(s.count(0) && s.count(1) && s.count(2)) << "both share the face a-b-c";
  }
}

TEST(TetImproveTest, AnEdgeOnAFacetFaceIsNeverRemoved) {
  TetMesh m = Bipyramid();
  // The triangle u-v-a now lies on a facet: the edge u-v must stay.
  m.faces.push_back({3, 4, 0});
  m.face_marker.push_back(kFirstSheetMarker + 6);
  m.face_piece.push_back(1);
  m.face_thickness_voxels.push_back(1);
  TetImproveReport report;
  ASSERT_TRUE(ImproveTetMesh(&m, {-0.5, -1, -0.6}, {1, 1, 0.6}, 5, {}, &report).ok());
  EXPECT_EQ(m.tets.size(), 3u);
  EXPECT_EQ(report.edge_removals, 0u);
}

// The work list's clock: an edit stamps the corners of its tetrahedron and nothing else, so
// a try at a tetrahedron away from the edit counts as unchanged and is not made again.
TEST(TetImproveTest, AnEditStampsOnlyTheCornersOfItsTetrahedron) {
  TetMesh m = Bipyramid();
  TetMeshEditor ed(&m);
  const uint64_t before = ed.clock();
  const Tet first = ed.tet(0), second = ed.tet(1);  // {u, v, a, b} and {u, v, b, c}
  EXPECT_TRUE(ed.UnchangedSince(first, before));
  ed.Kill(0);
  EXPECT_GT(ed.clock(), before);
  EXPECT_FALSE(ed.UnchangedSince(first, before));
  EXPECT_FALSE(ed.UnchangedSince(second, before)) << "it shares u, v and b";
  EXPECT_TRUE(ed.UnchangedSince(2u, before)) << "c is no corner of the killed tetrahedron";
  const uint64_t after_kill = ed.clock();
  ed.Add(first);
  EXPECT_FALSE(ed.UnchangedSince(3u, after_kill));
  EXPECT_TRUE(ed.UnchangedSince(2u, after_kill));
  const uint32_t w = ed.AddNode({0, 0, 0});
  EXPECT_FALSE(ed.UnchangedSince(w, after_kill)) << "a new vertex is as new as the clock";
  const uint64_t now = ed.clock();
  ed.Remeasure(1);
  EXPECT_FALSE(ed.UnchangedSince(2u, now)) << "remeasuring after a move stamps too";
}

TEST(TetImproveTest, AtTheBudgetOnlyFlipsThatAddNoTetrahedronRun) {
  // A flat bipyramid (u, v 0.2 off the ring's plane) as the two tetrahedra sharing a-b-c:
  // the three around u-v are the better (a 2-3 flip), one more tetrahedron.
  TetMesh m = Bipyramid();
  m.nodes[3].z = -0.2;
  m.nodes[4].z = 0.2;
  m.tets = {{0, 1, 2, 4}, {1, 0, 2, 3}};
  for (const Tet& t : m.tets) {
    ASSERT_GT(TetVolume(m.nodes[t[0]], m.nodes[t[1]], m.nodes[t[2]], m.nodes[t[3]]), 0);
  }
  TetImproveOptions at_budget;
  at_budget.max_tetrahedra = 2;
  TetMesh kept = m;
  TetImproveReport report;
  ASSERT_TRUE(ImproveTetMesh(&kept, {-0.5, -1, -0.2}, {1, 1, 0.2}, 5, at_budget, &report).ok());
  EXPECT_EQ(kept.tets.size(), 2u);
  EXPECT_EQ(report.face_removals, 0u);
  // One more allowed: the flip, and no insertion past it.
  TetImproveOptions room = at_budget;
  room.max_tetrahedra = 3;
  ASSERT_TRUE(ImproveTetMesh(&m, {-0.5, -1, -0.2}, {1, 1, 0.2}, 5, room, &report).ok());
  EXPECT_EQ(m.tets.size(), 3u);
  EXPECT_EQ(report.face_removals, 1u);
  EXPECT_EQ(report.inserted_vertices, 0u);
  EXPECT_GT(report.min_dihedral_after, report.min_dihedral_before);
}

// A square sheet of n x n quads at height z over [a, b] in x and y, voxel coordinates, its
// vertices lifted by `wave` alternately (nearly coplanar: the source of slivers).
TriangleMesh WavySquare(double a, double b, double z, int n, double wave) {
  TriangleMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      m.vertices.push_back(
          {a + (b - a) * i / n, a + (b - a) * j / n, z + ((i + j) % 2 ? wave : 0)});
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t v = j * (n + 1) + i;
      m.faces.push_back({v, v + 1, v + n + 2});
      m.faces.push_back({v, v + n + 2, v + n + 1});
    }
  m.face_piece.assign(m.faces.size(), 0);
  m.face_thickness_voxels.assign(m.faces.size(), 2);
  return m;
}

TEST(TetImproveTest, ImprovesTetgensMeshKeepingSheetsAndBox) {
  const TriangleMesh sheet = WavySquare(4, 16, 10, 6, 0.15);
  const Dims dims{20, 20, 20};
  // TetGen's own refinement, with points on the sheets and no lattice: the mesh with the
  // most for the pass to do, and sheet points that slide.
  VolumeMeshOptions off;
  off.improve.passes = 0;
  off.tetgen.max_volume = 4;
  off.tetgen.steiner_on_sheets = true;
  off.plc.lattice = 0;
  off.sliver_rounds = 0;  // the pass on TetGen's mesh of this PLC, not of a finer one
  VolumeMeshOptions on = off;
  on.improve = {};
  on.improve.sheet_move_voxels = 0;  // the PLC's sheet vertices stay (see SheetVerticesMove...)
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult before, BuildVolumeMesh(sheet, dims, {}, off));
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult after, BuildVolumeMesh(sheet, dims, {}, on));
  const TetImproveReport& r = after.improvement;
  EXPECT_EQ(before.improvement.passes, 0);
  // The report's before is TetGen's mesh; its after is what was measured.
  EXPECT_NEAR(r.min_dihedral_before, before.quality.min_dihedral.min, 1e-9);
  EXPECT_NEAR(r.mean_dihedral_before, before.quality.min_dihedral.mean, 1e-9);
  EXPECT_NEAR(r.min_dihedral_after, after.quality.min_dihedral.min, 1e-9);
  EXPECT_NEAR(r.mean_dihedral_after, after.quality.min_dihedral.mean, 1e-6);
  EXPECT_GT(r.edge_removals + r.face_removals, 0u);
  EXPECT_GT(r.smoothing_moves, 0u);
  // Better: the worst and the mean rise.
  EXPECT_GT(after.quality.min_dihedral.min, before.quality.min_dihedral.min + 1);
  EXPECT_GT(after.quality.min_dihedral.mean, before.quality.min_dihedral.mean + 3);
  EXPECT_GT(after.quality.radius_aspect.mean, before.quality.radius_aspect.mean);
  // Valid and conforming (BuildVolumeMesh checks these too).
  EXPECT_EQ(after.quality.inverted, 0u);
  EXPECT_NEAR(after.quality.volume, after.box_volume, 1e-9 * after.box_volume);
  EXPECT_EQ(after.conformity.conforming, after.conformity.sheet_triangles);
  EXPECT_EQ(after.conformity.orphan_faces, 0u);
  // The PLC's nodes come first in both and none goes: its own sheet vertices did not move.
  // The sheet vertices TetGen added may slide, but stay on their input triangle (within it,
  // as the area check of the conformity test above shows), or go where the sheets can do
  // without them (contracted: the nodes after are TetGen's, plus those inserted, less those
  // contracted, numbered again in order). Box faces stay on the box.
  SM_ASSERT_OK_AND_ASSIGN(const Plc plc, BuildPlc(sheet, dims, {}, on.plc));
  EXPECT_EQ(after.mesh.nodes.size() + r.contracted_edges + r.contracted_sheet_edges,
            before.mesh.nodes.size() + r.inserted_vertices);
  EXPECT_GT(r.sliding_vertices, 0u);
  absl::flat_hash_set<std::tuple<double, double, double>> tetgen_put;
  for (const Vec3& q : before.mesh.nodes) tetgen_put.insert({q.x, q.y, q.z});
  Vec3 lo = before.mesh.nodes[0], hi = lo;
  for (const Vec3& q : before.mesh.nodes) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], q[k]);
      hi[k] = std::max(hi[k], q[k]);
    }
  }
  absl::flat_hash_set<uint32_t> slid;
  for (size_t f = 0; f < after.mesh.faces.size(); ++f) {
    const auto& face = after.mesh.faces[f];
    if (after.mesh.face_piece[f] < 0) {
      int on_a_box_plane = 0;
      for (int k = 0; k < 3; ++k) {
        bool all = true;
        for (const double side : {lo[k], hi[k]}) {
          all = true;
          for (uint32_t v : face) all = all && after.mesh.nodes[v][k] == side;
          if (all) break;
        }
        on_a_box_plane += all;
      }
      EXPECT_EQ(on_a_box_plane, 1) << "box face " << f;
      continue;
    }
    for (uint32_t v : face) {
      const Vec3& p = after.mesh.nodes[v];
      if (v < plc.vertices.size()) {
        EXPECT_EQ(p, before.mesh.nodes[v]) << "PLC sheet vertex " << v;
        continue;
      }
      if (!tetgen_put.contains({p.x, p.y, p.z})) slid.insert(v);
      const Face& t = plc.sheet_triangles[after.mesh.face_marker[f] - kFirstSheetMarker];
      const Vec3 n = Normalized(
          Cross(plc.vertices[t[1]] - plc.vertices[t[0]], plc.vertices[t[2]] - plc.vertices[t[0]]));
      EXPECT_NEAR(Dot(p - plc.vertices[t[0]], n), 0, 1e-9) << "sheet node " << v;
    }
  }
  EXPECT_GT(slid.size(), 0u);
}

// TetGen's own refinement, with points on the sheets and no lattice: the mesh with the most
// for the improvement to do.
VolumeMeshOptions RefinedByTetgen() {
  VolumeMeshOptions o;
  o.tetgen.max_volume = 4;
  o.tetgen.steiner_on_sheets = true;
  o.plc.lattice = 0;
  return o;
}

// The smoothing runs on all cores in rounds of vertices that share no tetrahedron: the mesh
// is the same, to the bit, on one thread and on several.
TEST(TetImproveTest, TheSameMeshOnOneThreadAndOnAll) {
  const TriangleMesh sheet = WavySquare(4, 16, 10, 6, 0.15);
  const VolumeMeshOptions o = RefinedByTetgen();
  std::optional<VolumeMeshResult> one;
  {
    tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    SM_ASSERT_OK_AND_ASSIGN(one, BuildVolumeMesh(sheet, {20, 20, 20}, {}, o));
  }
  tbb::global_control several(tbb::global_control::max_allowed_parallelism, 4);
  SM_ASSERT_OK_AND_ASSIGN(const VolumeMeshResult all, BuildVolumeMesh(sheet, {20, 20, 20}, {}, o));
  ASSERT_GT(all.improvement.smoothing_moves, 100u);
  EXPECT_EQ(all.improvement.smoothing_moves, one->improvement.smoothing_moves);
  EXPECT_EQ(all.mesh.tets, one->mesh.tets);
  ASSERT_EQ(all.mesh.nodes.size(), one->mesh.nodes.size());
  for (size_t v = 0; v < all.mesh.nodes.size(); ++v) {
    ASSERT_EQ(all.mesh.nodes[v], one->mesh.nodes[v]) << "node " << v;
  }
}

// After the first pass only tetrahedra below improve.insert_again_below_degrees get a new
// vertex: at 0, four passes insert exactly what the first pass alone does (it is the same
// first pass); at insert_below_degrees, the later passes insert more.
TEST(TetImproveTest, AfterTheFirstPassOnlyTetrahedraBelowTheSecondBoundGetAVertex) {
  const TriangleMesh sheet = WavySquare(4, 16, 10, 6, 0.15);
  const VolumeMeshOptions o = RefinedByTetgen();
  auto inserted = [&](int passes, double again) -> uint64_t {
    VolumeMeshOptions v = o;
    v.improve.passes = passes;
    v.improve.insert_again_below_degrees = again;
    absl::StatusOr<VolumeMeshResult> r = BuildVolumeMesh(sheet, {20, 20, 20}, {}, v);
    EXPECT_TRUE(r.ok()) << r.status();
    return r.ok() ? r->improvement.inserted_vertices : 0;
  };
  const uint64_t first = inserted(1, 0);
  ASSERT_GT(first, 0u);
  EXPECT_EQ(inserted(4, 0), first);
  EXPECT_GT(inserted(4, 50), first);
}

TEST(TetImproveTest, SmoothingForTheBlendedShapeLiftsTheRadiusAspect) {
  // The default smoothing raises the mean of a blend of the smallest dihedral angle and
  // the radius aspect; weight 0 raises the dihedral angle alone, weight 1 the radius
  // aspect alone. Measured on this mesh: radius aspect 0.846 / 0.861 / 0.867, smallest
  // dihedral mean 53.9 / 53.7 / 52.6 degrees for weights 0 / 0.5 / 1.
  const TriangleMesh sheet = WavySquare(4, 16, 10, 6, 0.15);
  const Dims dims{20, 20, 20};
  VolumeMeshResult r[3];
  const double weights[3] = {0, 0.5, 1};
  for (int i = 0; i < 3; ++i) {
    VolumeMeshOptions o;
    o.improve.radius_weight = weights[i];
    SM_ASSERT_OK_AND_ASSIGN(r[i], BuildVolumeMesh(sheet, dims, {}, o));
    EXPECT_EQ(r[i].conformity.conforming, r[i].conformity.sheet_triangles);
    EXPECT_EQ(r[i].quality.inverted, 0u);
    EXPECT_GE(r[i].quality.min_dihedral.min, 10.0 - 1e-6) << "weight " << weights[i];
  }
  EXPECT_EQ(VolumeMeshOptions().improve.radius_weight, 0.5);
  EXPECT_GT(r[1].quality.radius_aspect.mean, r[0].quality.radius_aspect.mean + 0.005);
  EXPECT_GT(r[2].quality.radius_aspect.mean, r[1].quality.radius_aspect.mean);
  // The dihedral mean gives up little for it, and stays over the 45 degrees the defaults
  // keep.
  EXPECT_GT(r[1].quality.min_dihedral.mean, r[0].quality.min_dihedral.mean - 1.0);
  EXPECT_GT(r[1].quality.min_dihedral.mean, 45.0);
}

TEST(TetImproveTest, ZeroPassesLeavesTheMeshAsItIs) {
  TetMesh m = Bipyramid();
  const TetMesh copy = m;
  TetImproveOptions o;
  o.passes = 0;
  TetImproveReport report;
  ASSERT_TRUE(ImproveTetMesh(&m, {-0.5, -1, -0.6}, {1, 1, 0.6}, 5, o, &report).ok());
  EXPECT_EQ(m.tets, copy.tets);
  EXPECT_EQ(report.passes, 0);
  EXPECT_EQ(report.min_dihedral_after, report.min_dihedral_before);
}

// Two planar sheets crossing at right angles in a 20^3 box: A at z = 10 from face to face
// of the box in x and y, B at x = 9.5 inside it, sharing A's vertices on the junction
// line. A PLC sheet vertex may move within its ball only off the box, half as far on the
// junction; the ball holds it within its reach; a vertex whose face is split stays.
TEST(VertexFreedomTest, PlcSheetVerticesMoveOffTheBoxHalfAsFarAtJunctions) {
  TriangleMesh sheets;
  auto grid = [&](auto at, int nu, int nv, int32_t piece) {
    const uint32_t first = static_cast<uint32_t>(sheets.vertices.size());
    for (int j = 0; j <= nv; ++j)
      for (int i = 0; i <= nu; ++i) sheets.vertices.push_back(at(i, j));
    for (int j = 0; j < nv; ++j)
      for (int i = 0; i < nu; ++i) {
        const uint32_t v = first + j * (nu + 1) + i;
        sheets.faces.push_back({v, v + 1, v + nu + 2});
        sheets.faces.push_back({v, v + nu + 2, v + nu + 1});
        sheets.face_piece.insert(sheets.face_piece.end(), 2, piece);
      }
  };
  grid([](int i, int j) { return Vec3(-0.5 + 2 * i, -0.5 + 2 * j, 10); }, 10, 10, 0);
  grid([](int i, int j) { return Vec3(9.5, 3.5 + 2 * i, 4 + 2 * j); }, 6, 6, 1);
  // B's vertices on the junction line are A's: merge them.
  std::vector<uint32_t> same(sheets.vertices.size());
  for (uint32_t v = 0; v < same.size(); ++v) {
    same[v] = v;
    for (uint32_t w = 0; w < v; ++w) {
      if (sheets.vertices[w] == sheets.vertices[v]) {
        same[v] = w;
        break;
      }
    }
  }
  for (auto& f : sheets.faces)
    for (uint32_t& v : f) v = same[v];
  sheets.face_thickness_voxels.assign(sheets.faces.size(), 2);
  const Dims dims{20, 20, 20};
  VolumeMeshOptions o;
  o.improve.passes = 0;
  SM_ASSERT_OK_AND_ASSIGN(const VolumeMeshResult r, BuildVolumeMesh(sheets, dims, {}, o));
  SM_ASSERT_OK_AND_ASSIGN(const Plc plc, BuildPlc(sheets, dims, {}, o.plc));
  const uint32_t input = static_cast<uint32_t>(plc.vertices.size());
  const VertexFreedom none(r.mesh, plc.box_lo, plc.box_hi, input, 0);
  VertexFreedom fr(r.mesh, plc.box_lo, plc.box_hi, input, 1.0);
  std::vector<uint8_t> on_sheet(r.mesh.nodes.size(), 0);
  for (size_t f = 0; f < r.mesh.faces.size(); ++f) {
    if (r.mesh.face_piece[f] < 0) continue;
    for (uint32_t v : r.mesh.faces[f]) on_sheet[v] = 1;
  }
  int balls = 0, junction = 0, box = 0;
  for (uint32_t v = 0; v < input; ++v) {
    EXPECT_FALSE(none.in_ball(v));
    if (!on_sheet[v]) {
      EXPECT_FALSE(fr.in_ball(v)) << v;
      continue;
    }
    const Vec3& p = r.mesh.nodes[v];
    const bool at_box =
        p.x == -0.5 || p.x == 19.5 || p.y == -0.5 || p.y == 19.5 || p.z == -0.5 || p.z == 19.5;
    const bool at_junction = p.x == 9.5 && p.z == 10 && p.y >= 3.5 && p.y <= 15.5;
    EXPECT_EQ(fr.in_ball(v), !at_box) << v << " at " << p.x << "," << p.y << "," << p.z;
    if (at_junction) {
      EXPECT_NEAR(Norm(fr.Place(v, p + Vec3(0, 0, 5)) - p), 0.5, 1e-12) << v;
    } else if (!at_box) {
      EXPECT_NEAR(Norm(fr.Place(v, p + Vec3(0, 0, 5)) - p), 1.0, 1e-12) << v;
    }
    balls += fr.in_ball(v);
    junction += at_junction;
    box += at_box;
  }
  EXPECT_EQ(junction, 7);  // y = 3.5 ... 15.5
  EXPECT_GT(box, 0);
  EXPECT_GT(balls, 80);
  // Within the ball any way; past it, back onto its sphere.
  uint32_t v = 0;
  while (!fr.in_ball(v) || r.mesh.nodes[v].x == 9.5) ++v;
  const Vec3 a = r.mesh.nodes[v];
  EXPECT_EQ(fr.Constrain(v, {0.3, -0.2, 0.1}), Vec3(0.3, -0.2, 0.1));
  EXPECT_EQ(fr.Place(v, a + Vec3(0.5, 0, 0)), a + Vec3(0.5, 0, 0));
  EXPECT_NEAR(Norm(fr.Place(v, a + Vec3(0, 3, 4)) - a), 1.0, 1e-12);
  EXPECT_NEAR(Norm(fr.Place(v, a + Vec3(0, 3, 4)) - (a + Vec3(0, 0.6, 0.8))), 0, 1e-12);
  fr.Freeze(v);
  EXPECT_FALSE(fr.in_ball(v));
  EXPECT_EQ(fr.in_balls(), static_cast<uint32_t>(balls - 1));
}

// Two tetrahedra on either side of the sheet face a-b-c (every hull face a sheet face, so
// only the inner point moves), the upper split by a free point p just above a-b-c: the
// tetrahedron a-b-c-p is a sliver that no flip removes (a-b-c is a facet face).
TetMesh SplitBipyramid(const Vec3& p) {
  TetMesh m = Bipyramid();
  const uint32_t a = 0, b = 1, c = 2, u = 3, v = 4;
  m.nodes.push_back(p);
  const uint32_t q = 5;
  m.tets = {{b, a, c, u}, {q, b, c, v}, {a, q, c, v}, {a, b, q, v}, {a, b, c, q}};
  // Orient them all positively (the test's own layout, not the library's business).
  for (Tet& t : m.tets) {
    if (TetVolume(m.nodes[t[0]], m.nodes[t[1]], m.nodes[t[2]], m.nodes[t[3]]) < 0) {
      std::swap(t[0], t[1]);
    }
  }
  m.faces.push_back({a, b, c});
  m.face_marker.push_back(kFirstSheetMarker + 6);
  m.face_piece.push_back(0);
  m.face_thickness_voxels.push_back(1);
  return m;
}

TEST(TetContractionTest, AFreePointPressedOntoASheetFaceMergesIntoACorner) {
  TetMesh m = SplitBipyramid({0.1, 0.05, 0.02});
  const double volume = Volume(m), before = Worst(m);
  ASSERT_LT(before, 5) << "a sliver to begin with";
  TetMeshEditor ed(&m);
  VertexFreedom freedom(m, {-0.5, -1, -0.6}, {1, 1, 0.6}, 5);
  ASSERT_TRUE(freedom.interior(5));
  ASSERT_FALSE(freedom.interior(0)) << "a sheet vertex never goes";
  uint32_t sliver = 0;
  for (uint32_t t = 0; t < m.tets.size(); ++t) {
    if (ed.quality(t) < ed.quality(sliver)) sliver = t;
  }
  ASSERT_TRUE(ContractEdgeOf(ed, freedom, sliver));
  ed.Finish();
  EXPECT_EQ(m.tets.size(), 2u);
  EXPECT_TRUE(ed.star(5).empty());
  EXPECT_NEAR(Volume(m), volume, 1e-12);
  EXPECT_GT(Worst(m), before + 10);
  EXPECT_EQ(m.RemoveUnusedNodes(), 1u);
  EXPECT_EQ(m.nodes.size(), 5u);
  for (const Tet& t : m.tets) {
    for (uint32_t v : t) EXPECT_LT(v, 5u);
  }
}

TEST(TetContractionTest, APointOnASheetOrOneWhoseMergeWouldFoldStays) {
  {
    // p on a sheet face: not interior, never contracted.
    TetMesh m = SplitBipyramid({0.1, 0.05, 0.02});
    m.faces.push_back({0, 1, 5});
    m.face_marker.push_back(kFirstSheetMarker + 7);
    m.face_piece.push_back(0);
    m.face_thickness_voxels.push_back(1);
    TetMeshEditor ed(&m);
    VertexFreedom freedom(m, {-0.5, -1, -0.6}, {1, 1, 0.6}, 5);
    for (uint32_t t = 0; t < m.tets.size(); ++t) EXPECT_FALSE(ContractEdgeOf(ed, freedom, t));
  }
  {
    // Every tetrahedron good already: no contraction raises the worst of p's star.
    TetMesh m = SplitBipyramid({0.0, 0.0, 0.25});
    TetMeshEditor ed(&m);
    VertexFreedom freedom(m, {-0.5, -1, -0.6}, {1, 1, 0.6}, 5);
    const double before = Worst(m);
    bool any = false;
    for (uint32_t t = 1; t < m.tets.size(); ++t) any |= ContractEdgeOf(ed, freedom, t);
    if (any) {
      ed.Finish();
      EXPECT_GT(Worst(m), before) << "a contraction only where it raises the worst";
    }
  }
}

// The bipyramid's middle face a-b-c a sheet triangle of its own (marker 20) that an added
// sheet vertex q splits in three, q a short way from corner a: the pieces at a are needles
// and the tetrahedra on them slivers. `input_nodes` says whether q is the PLC's own.
TetMesh SheetSplitNearCorner() {
  TetMesh m = Bipyramid();
  const uint32_t a = 0, b = 1, c = 2, u = 3, v = 4, q = 5;
  m.nodes.push_back(m.nodes[a] * 0.96 + m.nodes[b] * 0.025 + m.nodes[c] * 0.015);
  m.tets = {{a, b, q, v}, {b, c, q, v}, {c, a, q, v}, {b, a, q, u}, {c, b, q, u}, {a, c, q, u}};
  for (Tet& t : m.tets) {
    if (TetVolume(m.nodes[t[0]], m.nodes[t[1]], m.nodes[t[2]], m.nodes[t[3]]) < 0) {
      std::swap(t[0], t[1]);
    }
  }
  for (const std::array<uint32_t, 3>& f :
       {std::array<uint32_t, 3>{a, b, q}, {b, c, q}, {c, a, q}}) {
    m.faces.push_back(f);
    m.face_marker.push_back(kFirstSheetMarker + 20);
    m.face_piece.push_back(1);
    m.face_thickness_voxels.push_back(2);
  }
  return m;
}

TEST(TetContractionTest, AnAddedSheetVertexByACornerMergesIntoItAlongItsSheet) {
  TetMesh m = SheetSplitNearCorner();
  const double volume = Volume(m), before = Worst(m);
  ASSERT_LT(before, 5) << "slivers on the needles to begin with";
  TetMeshEditor ed(&m);
  VertexFreedom freedom(m, {-0.5, -1, -0.6}, {1, 1, 0.6}, 5);
  ASSERT_TRUE(freedom.slides(5)) << "q slides within its sheet triangle";
  ASSERT_FALSE(freedom.interior(5));
  EXPECT_FALSE(ContractEdgeOf(ed, freedom, 0)) << "not a free corner";
  uint32_t sliver = 0;
  for (uint32_t t = 0; t < m.tets.size(); ++t) {
    if (ed.quality(t) < ed.quality(sliver)) sliver = t;
  }
  ASSERT_TRUE(ContractSheetEdgeOf(ed, freedom, sliver));
  ed.Finish();
  // The bipyramid again: two tetrahedra on the one sheet face a-b-c, which keeps its marker,
  // piece and thickness; the six hull faces as they were.
  EXPECT_EQ(m.tets.size(), 2u);
  EXPECT_NEAR(Volume(m), volume, 1e-12);
  EXPECT_GT(Worst(m), before + 20);
  ASSERT_EQ(m.faces.size(), 7u);
  ASSERT_EQ(m.face_marker.size(), 7u);
  ASSERT_EQ(m.face_piece.size(), 7u);
  ASSERT_EQ(m.face_thickness_voxels.size(), 7u);
  EXPECT_EQ(SortedFace(m.faces[6][0], m.faces[6][1], m.faces[6][2]), SortedFace(0, 1, 2));
  EXPECT_EQ(m.face_marker[6], kFirstSheetMarker + 20);
  EXPECT_EQ(m.face_piece[6], 1);
  EXPECT_EQ(m.face_thickness_voxels[6], 2.0f);
  for (size_t f = 0; f < 6; ++f) EXPECT_EQ(m.face_marker[f], kFirstSheetMarker + int32_t(f));
  EXPECT_EQ(m.RemoveUnusedNodes(), 1u);
}

TEST(TetContractionTest, ThePlcsOwnSheetVerticesAndMergesOffTheSheetStay) {
  {
    // q one of the PLC's vertices: the sheets as the surface gave them, never merged.
    TetMesh m = SheetSplitNearCorner();
    TetMeshEditor ed(&m);
    VertexFreedom freedom(m, {-0.5, -1, -0.6}, {1, 1, 0.6}, 6);
    ASSERT_FALSE(freedom.slides(5));
    for (uint32_t t = 0; t < m.tets.size(); ++t) EXPECT_FALSE(ContractSheetEdgeOf(ed, freedom, t));
  }
  {
    // b-c-q of another input triangle: q is a corner where two input triangles meet, on
    // no one line, and slides in neither; it stays.
    TetMesh m = SheetSplitNearCorner();
    m.face_marker[7] = kFirstSheetMarker + 21;
    TetMeshEditor ed(&m);
    VertexFreedom freedom(m, {-0.5, -1, -0.6}, {1, 1, 0.6}, 5);
    EXPECT_FALSE(freedom.slides(5));
    for (uint32_t t = 0; t < m.tets.size(); ++t) EXPECT_FALSE(ContractSheetEdgeOf(ed, freedom, t));
  }
}

}  // namespace
}  // namespace sheetmesh
