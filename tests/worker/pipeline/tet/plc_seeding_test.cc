// The points the PLC seeds off the sheets: the graded lattice and the box's points.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "tests/testing/status_matchers.h"
#include "tests/worker/pipeline/tet/tet_test_shapes.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/plc.h"
#include "worker/pipeline/tet/plc_parts.h"

namespace sheetmesh {
namespace {

// The seeds are offset by at most kSeedJitterVoxels / 2 per coordinate (plc_types.h).
constexpr double kSlack = 2 * kSeedJitterVoxels;

using ::sheetmesh::testing::ClosestPair;
using ::sheetmesh::testing::DistanceToSheets;
using ::sheetmesh::testing::Square;
using ::testing::ElementsAre;

TEST(PlcTest, BoxSeedsLieOnTheBoxInItsFacetsGradedAwayFromTheSheets) {
  // The 40 x 40 sheet of the lattice test below in a 60^3 box [-0.5, 59.5]^3, spacing 5:
  // level 0 (h = 5) lies 3 to 13 from the sheet, level 1 (h = 10) 13 to 33 (grading 0.4).
  const TriangleMesh sheet = Square(10, 50, 30, 8);
  PlcOptions o;
  o.lattice = 1.0;
  o.grading = 0.4;
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
    EXPECT_GT(d, 3.0 - kSlack);
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
  EXPECT_NEAR(ClosestPair(near), 5.0, kSlack);
  // Not seeded unless asked.
  o.seed_box = false;
  SM_ASSERT_OK_AND_ASSIGN(Plc plain, BuildPlc(sheet, {60, 60, 60}, {}, o));
  EXPECT_EQ(plain.box_points, 0u);
}

TEST(PlcTest, ASheetNearlyParallelToABoxFaceGivesTheFacePointsBeneathItsVertices) {
  // The 40 x 40 sheet (edges 5) 2 voxels over the bottom face z = -0.5 of a 60^3 box: the
  // lattice's first band starts 3 from the sheet, so no seeded point of the face lies
  // beneath it; each sheet vertex then gives the face one straight beneath it, but those
  // within 2.5 (half a spacing) of the face's points beside the sheet.
  const TriangleMesh sheet = Square(10, 50, 1.5, 8);
  PlcOptions o;
  o.lattice = 1.0;
  o.seed_box = true;
  SM_ASSERT_OK_AND_ASSIGN(Plc plc, BuildPlc(sheet, {60, 60, 60}, {}, o));
  const uint32_t first = 8 + 81, end = first + plc.box_points;
  std::vector<Vec3> beneath;
  for (uint32_t v = first; v < end; ++v) {
    const Vec3& p = plc.vertices[v];
    if (std::abs(p.z + 0.5) < 1e-12 && p.x > 10 - 1 && p.x < 50 + 1 && p.y > 10 - 1 &&
        p.y < 50 + 1) {
      beneath.push_back(p);
    }
  }
  // Every interior vertex (7 x 7) has its point, offset in the face by the seeds' jitter.
  for (int j = 1; j < 8; ++j) {
    for (int i = 1; i < 8; ++i) {
      const Vec3 want(10 + 5 * i, 10 + 5 * j, -0.5);
      const bool found = std::any_of(beneath.begin(), beneath.end(), [&](const Vec3& p) {
        return std::abs(p.x - want.x) <= kSlack && std::abs(p.y - want.y) <= kSlack &&
               p.z == want.z;
      });
      EXPECT_TRUE(found) << "no face point beneath (" << want.x << ", " << want.y << ")";
    }
  }
  EXPECT_LE(beneath.size(), 81u);
  EXPECT_GE(ClosestPair(beneath), 5.0 - kSlack);
  // Each is a point of the bottom facet (index 4: the low face across z).
  for (const auto& poly : plc.facets[4].polygons) {
    if (poly.size() == 1 && std::abs(plc.vertices[poly[0]].z + 0.5) < 1e-12) {
      EXPECT_GE(poly[0], first);
    }
  }
  // A sheet standing upright on the face gives it none beside its trace.
  const TriangleMesh upright = Square(10, 50, 30, 8, 0, 3, 0);  // x = 30, over y and z
  SM_ASSERT_OK_AND_ASSIGN(Plc wall, BuildPlc(upright, {60, 60, 60}, {}, o));
  for (uint32_t v = 8 + 81; v < 8 + 81 + wall.box_points; ++v) {
    EXPECT_GT(DistanceToSheets(wall, wall.vertices[v]), 3.0 - kSlack);
  }
}

TEST(PlcTest, LatticeSeedsKeepOffTheSheetsAndTheBoxAndCoarsenAway) {
  // A 40 x 40 square sheet of 8 x 8 quads (edges 5 and 7.07 voxels: median 5) in a 60^3
  // box; the lattice at 1 x the median edge has spacing 5 next to the sheet.
  const TriangleMesh sheet = Square(10, 50, 30, 8);
  PlcOptions o;
  o.lattice = 1.0;
  o.grading = 1.0;
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
  // Seeds stay 0.6 spacings off the sheet and the box (box [-0.5, 59.5]^3); at grading 1
  // level 0 (spacing 5) reaches 0.6 * 5 + 5 = 8 from the sheet, levels 1 and 2 (spacings 10
  // and 20) fill the rest (level 3's spacing, 40, is over half the box's 60): beyond 15.5
  // every seed is theirs.
  std::vector<Vec3> near, far;
  for (size_t i = first_seed; i < plc.vertices.size(); ++i) {
    const Vec3& p = plc.vertices[i];
    const double d = DistanceToSheets(plc, p);
    EXPECT_GT(d, 3.0 - kSlack);
    for (int k = 0; k < 3; ++k) {
      EXPECT_GE(p[k], -0.5 + 3.0 - kSlack);
      EXPECT_LE(p[k], 59.5 - 3.0 + kSlack);
    }
    (d <= 15.5 ? near : far).push_back(p);
  }
  ASSERT_FALSE(near.empty());
  ASSERT_FALSE(far.empty());
  // A BCC lattice's nearest neighbours are sqrt(3)/2 spacings apart.
  EXPECT_NEAR(ClosestPair(near), std::sqrt(3.0) / 2 * 5, kSlack);
  EXPECT_GE(ClosestPair(far), std::sqrt(3.0) / 2 * 10 - kSlack);
  // None at 0.
  PlcOptions off;
  off.lattice = 0;
  SM_ASSERT_OK_AND_ASSIGN(Plc plain, BuildPlc(sheet, {60, 60, 60}, {}, off));
  EXPECT_EQ(plain.seed_points, 0u);
  EXPECT_EQ(plain.vertices.size(), first_seed);
}

TEST(PlcTest, TheGradedLatticeDoublesItsSpacingEveryBandOutToTheBoxScale) {
  // Spacing 5 in a 200^3 box: levels of spacing 5, 10, 20, 40 and 80 (160 is over half of
  // 200). Level 0 starts 0.6 spacings (3) off the sheets; each band is 1 / grading of its
  // own spacings wide.
  const Vec3 lo{-0.5, -0.5, -0.5}, hi{199.5, 199.5, 199.5};
  const LatticeLevels slow = GradeLattice(lo, hi, 5, 0.4);
  EXPECT_THAT(slow.spacing, ElementsAre(5, 10, 20, 40, 80));
  EXPECT_THAT(slow.inner, ElementsAre(3, 15.5, 40.5, 90.5, 190.5));
  EXPECT_DOUBLE_EQ(slow.SpacingAt(2.9), 0);  // TetGen's, next to the sheets
  EXPECT_DOUBLE_EQ(slow.SpacingAt(10), 5);
  EXPECT_DOUBLE_EQ(slow.SpacingAt(20), 10);
  EXPECT_DOUBLE_EQ(slow.SpacingAt(60), 20);
  EXPECT_DOUBLE_EQ(slow.SpacingAt(95), 40);
  EXPECT_DOUBLE_EQ(slow.SpacingAt(200), 80);
  EXPECT_DOUBLE_EQ(slow.SpacingAt(1000), 80);
  // Grading 1: each band one spacing wide, [3, 8), [8, 18), [18, 38), [38, 78), [78, ...).
  const LatticeLevels fast = GradeLattice(lo, hi, 5, 1.0);
  EXPECT_THAT(fast.inner, ElementsAre(3, 8, 18, 38, 78));
  EXPECT_DOUBLE_EQ(fast.SpacingAt(10), 10);
  EXPECT_DOUBLE_EQ(fast.SpacingAt(30), 20);
  EXPECT_DOUBLE_EQ(fast.SpacingAt(50), 40);
  // A box 2000 across has room for 8 levels (640 fits twice in 2000, 1280 does not).
  const LatticeLevels big = GradeLattice(lo, {1999.5, 1999.5, 1999.5}, 5, 1.0);
  ASSERT_EQ(big.spacing.size(), 8u);
  EXPECT_DOUBLE_EQ(big.spacing.back(), 640);
  // No lattice without a spacing or a grading.
  EXPECT_TRUE(GradeLattice(lo, hi, 0, 1.0).spacing.empty());
  EXPECT_TRUE(GradeLattice(lo, hi, 5, 0).spacing.empty());
  EXPECT_DOUBLE_EQ(GradeLattice(lo, hi, 0, 1.0).SpacingAt(50), 0);
}

TEST(PlcTest, TheSeededLatticeHasTheGradedSpacingAtEachDistance) {
  // The 40 x 40 sheet (median edge 5) at the middle of a 200^3 box, lattice spacing 5 at
  // grading 1: the seeds between 38 and 78 voxels belong to level 3 (spacing 40), those
  // between 8 and 18 to level 1 (spacing 10); a BCC lattice's nearest neighbours are
  // sqrt(3)/2 spacings apart. (The coarsest level, 80, keeps 48 off the box: it has no
  // room beyond 78 from this sheet.)
  const TriangleMesh sheet = Square(80, 120, 100, 8);
  PlcOptions o;
  o.lattice = 1.0;
  o.grading = 1.0;
  SM_ASSERT_OK_AND_ASSIGN(Plc plc, BuildPlc(sheet, {200, 200, 200}, {}, o));
  EXPECT_EQ(plc.lattice_levels, 5u);
  EXPECT_DOUBLE_EQ(plc.lattice_spacing, 5);
  EXPECT_DOUBLE_EQ(plc.lattice_coarsest, 80);
  std::vector<Vec3> level1, level3;
  for (size_t i = plc.vertices.size() - plc.seed_points; i < plc.vertices.size(); ++i) {
    const double d = DistanceToSheets(plc, plc.vertices[i]);
    EXPECT_GT(d, 3.0 - kSlack);
    if (d >= 8 && d < 18) level1.push_back(plc.vertices[i]);
    if (d >= 38 && d < 78) level3.push_back(plc.vertices[i]);
  }
  ASSERT_GE(level1.size(), 2u);
  ASSERT_GE(level3.size(), 2u);
  EXPECT_NEAR(ClosestPair(level1), std::sqrt(3.0) / 2 * 10, kSlack);
  EXPECT_NEAR(ClosestPair(level3), std::sqrt(3.0) / 2 * 40, kSlack);
  // A grading of 0.4 keeps each level 2.5 of its spacings wide: more seeds.
  o.grading = 0.4;
  SM_ASSERT_OK_AND_ASSIGN(Plc slow, BuildPlc(sheet, {200, 200, 200}, {}, o));
  EXPECT_GT(slow.seed_points, plc.seed_points);
}

TEST(PlcTest, AThinBoxKeepsTheLatticeAtTheSpacingsThatFitIt) {
  // The same sheet at z = 10 in a box 80 x 80 x 16 ([-0.5, 15.5] in z): level 1's spacing,
  // 10, is over half of 16, so level 0 (spacing 5) fills the whole box, out to 27 voxels
  // from the sheet, where the box 40 thick below has level 1's spacing 10.
  PlcOptions o;
  o.lattice = 1.0;
  o.grading = 1.0;
  // The seeds beyond 15.5 from the sheet.
  auto far_seeds = [](const Plc& plc) {
    std::vector<Vec3> far;
    for (size_t i = plc.vertices.size() - plc.seed_points; i < plc.vertices.size(); ++i) {
      if (DistanceToSheets(plc, plc.vertices[i]) > 15.5) far.push_back(plc.vertices[i]);
    }
    return far;
  };
  SM_ASSERT_OK_AND_ASSIGN(Plc thin, BuildPlc(Square(10, 50, 10, 8), {80, 80, 16}, {}, o));
  ASSERT_GT(thin.seed_points, 0u);
  for (size_t i = thin.vertices.size() - thin.seed_points; i < thin.vertices.size(); ++i) {
    EXPECT_GE(thin.vertices[i].z, -0.5 + 3.0 - kSlack);
    EXPECT_LE(thin.vertices[i].z, 15.5 - 3.0 + kSlack);
  }
  std::vector<Vec3> far = far_seeds(thin);
  ASSERT_GE(far.size(), 2u);
  EXPECT_NEAR(ClosestPair(far), std::sqrt(3.0) / 2 * 5, kSlack);
  // A box 40 thick has room for level 1 (2 x 10 = 20 <= 40): coarser seeds out there.
  SM_ASSERT_OK_AND_ASSIGN(Plc thick, BuildPlc(Square(10, 50, 10, 8), {80, 80, 40}, {}, o));
  far = far_seeds(thick);
  ASSERT_GE(far.size(), 2u);
  EXPECT_GE(ClosestPair(far), std::sqrt(3.0) / 2 * 10 - kSlack);
}

TEST(PlcTest, MovingTheSeedsMovesOnlyTheSeedsByAtMostHalfTheStepTheSameWayForASalt) {
  const TriangleMesh sheet = Square(10, 50, 30, 8);
  SM_ASSERT_OK_AND_ASSIGN(const Plc plc, BuildPlc(sheet, {60, 60, 60}, {}, {}));
  ASSERT_GT(plc.seed_points, 0u);
  const size_t first_seed = plc.vertices.size() - plc.seed_points;
  Plc once = plc, again = plc, other = plc;
  MoveSeeds(1, 2e-3, &once);
  MoveSeeds(1, 2e-3, &again);
  MoveSeeds(2, 2e-3, &other);
  double farthest = 0;
  size_t moved = 0, differ = 0;
  for (size_t i = 0; i < plc.vertices.size(); ++i) {
    const Vec3 d = once.vertices[i] - plc.vertices[i];
    if (i < first_seed) {
      EXPECT_EQ(Norm(d), 0.0) << "vertex " << i << " is the box's or a sheet's";
      continue;
    }
    for (int k = 0; k < 3; ++k) farthest = std::max(farthest, std::abs(d[k]));
    moved += Norm(d) > 0;
    EXPECT_EQ(Norm(again.vertices[i] - once.vertices[i]), 0.0);
    differ += Norm(other.vertices[i] - once.vertices[i]) > 0;
  }
  EXPECT_LE(farthest, 1e-3);
  EXPECT_GT(farthest, 5e-4);
  EXPECT_EQ(moved, plc.seed_points);
  EXPECT_EQ(differ, plc.seed_points);  // another salt, another offset
}

}  // namespace
}  // namespace sheetmesh
