#include "worker/pipeline/surface/radius_search.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/testing/shapes.h"
#include "tests/testing/status_matchers.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::StatusIs;

SheetAnalysis Sheet() {
  // A rough, holed sheet: similarity falls with r.
  return *AnalyzeSheet(testing::ShapeSet({72, 72, 20}, [](double x, double y, double z) {
    const double mid = 10 + 2 * std::sin(x / 6) * std::cos(y / 7);
    return x > 2 && y > 2 && x < 70 && y < 70 && std::abs(z - mid) <= 2 &&
           std::hypot(x - 30, y - 40) > 7;
  }));
}

TEST(RadiusSearchTest, BestGoalReturnsTheBestTrial) {
  const SheetAnalysis sheet = Sheet();
  RadiusSearchOptions o;
  o.goal = RadiusGoal::kBestSimilarity;
  o.max_radius_voxels = 14;
  SM_ASSERT_OK_AND_ASSIGN(RadiusChoice c, SearchRadius(sheet, SurfaceOptions(), o));
  ASSERT_GE(c.trials.size(), 3u);
  double best = -1;
  for (const RadiusTrial& t : c.trials) best = std::max(best, t.similarity);
  for (const RadiusTrial& t : c.trials) {
    if (t.radius == c.radius) EXPECT_EQ(t.similarity, best);
  }
}

TEST(RadiusSearchTest, TargetGoalReturnsTheLargestRadiusReachingIt) {
  const SheetAnalysis sheet = Sheet();
  RadiusSearchOptions o;
  o.goal = RadiusGoal::kTargetSimilarity;
  o.target_similarity = 0.8;
  o.max_radius_voxels = 20;
  SM_ASSERT_OK_AND_ASSIGN(RadiusChoice c, SearchRadius(sheet, SurfaceOptions(), o));
  ASSERT_TRUE(c.target_reached);
  double chosen_sim = -1, fewest = 1e18;
  for (const RadiusTrial& t : c.trials) {
    if (t.radius == c.radius) {
      chosen_sim = t.similarity;
      fewest = t.triangles;
    }
  }
  EXPECT_GE(chosen_sim, 0.8);
  // Every larger r tried fell short of the target.
  for (const RadiusTrial& t : c.trials) {
    if (t.radius > c.radius) EXPECT_LT(t.similarity, 0.8) << "r = " << t.radius;
    if (t.similarity >= 0.8) EXPECT_GE(t.triangles, fewest);
  }
}

TEST(RadiusSearchTest, UnreachableTargetFallsBackToTheBestRadius) {
  const SheetAnalysis sheet = Sheet();
  RadiusSearchOptions o;
  o.goal = RadiusGoal::kTargetSimilarity;
  o.target_similarity = 0.9999;
  o.max_radius_voxels = 8;
  SM_ASSERT_OK_AND_ASSIGN(RadiusChoice c, SearchRadius(sheet, SurfaceOptions(), o));
  EXPECT_FALSE(c.target_reached);
  EXPECT_GT(c.radius, 0);
}

TEST(RadiusSearchTest, TriangleGoalMeetsTheBudgetWithinFivePercent) {
  const SheetAnalysis sheet = Sheet();
  for (bool decimate : {false, true}) {
    for (uint64_t n : {60, 150, 400, 900}) {
      RadiusSearchOptions o;
      o.goal = RadiusGoal::kTriangles;
      o.target_triangles = n;
      o.decimate = decimate;
      SM_ASSERT_OK_AND_ASSIGN(RadiusChoice c, SearchRadius(sheet, SurfaceOptions(), o));
      EXPECT_TRUE(c.target_reached) << n << ": " << c.message;
      if (!decimate) EXPECT_EQ(c.decimate_to, 0u);
      SurfaceOptions s;
      s.scvd.radius_voxels = c.radius;
      s.target_faces = c.decimate_to;
      SM_ASSERT_OK_AND_ASSIGN(SurfaceResult built, BuildSurface(sheet, s));
      EXPECT_NEAR(double(built.mesh.num_faces()), double(n), 0.05 * n) << "r = " << c.radius;
      if (c.decimate_to > 0) {
        // Decimated from the dual mesh of about four times the count (or the finest, at
        // r_min), not from the one at the count (a search that stopped just above 4 n once
        // fell back to the coarsest).
        ASSERT_TRUE(built.decimation.has_value());
        if (c.radius > o.min_radius_voxels) {
          EXPECT_GE(built.decimation->faces_before, 3 * n) << "r = " << c.radius;
        }
      }
    }
  }
}

TEST(RadiusSearchTest, TriangleGoalBelowTheOutlineOrBeyondTheFinestIsSaid) {
  const SheetAnalysis sheet = Sheet();
  RadiusSearchOptions o;
  o.goal = RadiusGoal::kTriangles;
  o.target_triangles = 0;
  EXPECT_THAT(SearchRadius(sheet, SurfaceOptions(), o),
              StatusIs(absl::StatusCode::kInvalidArgument, ::testing::HasSubstr("triangles = 0")));
  // Two triangles: fewer than the coarsest mesh (the largest r) has; the message names it.
  // (Decimating, the search says where the collapses stopped; the pipeline refuses that.)
  o.decimate = false;
  o.target_triangles = 2;
  o.max_radius_voxels = 12;
  SurfaceOptions coarsest;
  coarsest.scvd.radius_voxels = 12;
  SM_ASSERT_OK_AND_ASSIGN(SurfaceResult c, BuildSurface(sheet, coarsest));
  EXPECT_THAT(
      SearchRadius(sheet, SurfaceOptions(), o),
      StatusIs(absl::StatusCode::kInvalidArgument,
               ::testing::HasSubstr(absl::StrCat(c.mesh.num_faces(), " at the largest r"))));
  // More than the smallest r gives: the finest mesh, said not to reach it.
  o.target_triangles = 1000000;
  o.max_radius_voxels = 0;
  o.min_radius_voxels = 3;
  SM_ASSERT_OK_AND_ASSIGN(RadiusChoice fine, SearchRadius(sheet, SurfaceOptions(), o));
  EXPECT_FALSE(fine.target_reached);
  EXPECT_DOUBLE_EQ(fine.radius, 3);
  EXPECT_THAT(fine.message, ::testing::HasSubstr("1000000 triangles"));
  o.decimate = true;
  SM_ASSERT_OK_AND_ASSIGN(RadiusChoice finest, SearchRadius(sheet, SurfaceOptions(), o));
  EXPECT_FALSE(finest.target_reached);
  EXPECT_THAT(finest.message, ::testing::HasSubstr("1000000 triangles"));
  o.target_triangles = 2;
  o.max_radius_voxels = 12;
  o.min_radius_voxels = 2;
  SM_ASSERT_OK_AND_ASSIGN(RadiusChoice stopped, SearchRadius(sheet, SurfaceOptions(), o));
  EXPECT_FALSE(stopped.target_reached);
  EXPECT_THAT(stopped.message, ::testing::HasSubstr("decimation stopped at"));
}

TEST(RadiusSearchTest, BadRangesAreInvalidArgument) {
  const SheetAnalysis sheet = Sheet();
  RadiusSearchOptions o;
  o.min_radius_voxels = 0;
  EXPECT_THAT(SearchRadius(sheet, SurfaceOptions(), o),
              StatusIs(absl::StatusCode::kInvalidArgument));
  o.min_radius_voxels = 9;
  o.max_radius_voxels = 4;
  EXPECT_THAT(SearchRadius(sheet, SurfaceOptions(), o),
              StatusIs(absl::StatusCode::kInvalidArgument));
  o = {};
  o.goal = RadiusGoal::kTargetSimilarity;
  o.target_similarity = 1.5;
  EXPECT_THAT(SearchRadius(sheet, SurfaceOptions(), o),
              StatusIs(absl::StatusCode::kInvalidArgument));
}

}  // namespace
}  // namespace sheetmesh
