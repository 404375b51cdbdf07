#include "worker/pipeline/surface/radius_search.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/testing/shapes.h"
#include "tests/testing/status_matchers.h"
#include "worker/pipeline/similarity/mesh_model.h"
#include "worker/pipeline/similarity/similarity.h"

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

// The surface the search hands back is the chosen r's, as BuildSurface gives it, and scores
// what its trial said.
void ExpectTheChosenSurface(const SheetAnalysis& sheet, const RadiusSearchResult& found) {
  SurfaceOptions s;
  s.scvd.radius_voxels = found.choice.radius;
  s.triangles = found.choice.decimated_to;
  SM_ASSERT_OK_AND_ASSIGN(SurfaceResult again, BuildSurface(sheet, s));
  EXPECT_EQ(found.surface.mesh.faces, again.mesh.faces) << "r = " << found.choice.radius;
  EXPECT_EQ(found.surface.mesh.face_thickness_voxels, again.mesh.face_thickness_voxels);
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet model, VoxelizePrisms(found.surface.mesh, sheet.set.dims()));
  for (const RadiusTrial& t : found.choice.trials) {
    if (t.radius == found.choice.radius && t.scored &&
        t.decimated_to == found.choice.decimated_to) {
      EXPECT_DOUBLE_EQ(ScoreModel(model, sheet.set).similarity, t.similarity);
    }
  }
}

TEST(RadiusSearchTest, BestGoalReturnsTheBestTrial) {
  const SheetAnalysis sheet = Sheet();
  RadiusSearchOptions o;
  o.goal = RadiusGoal::kBestSimilarity;
  o.max_radius_voxels = 14;
  SM_ASSERT_OK_AND_ASSIGN(RadiusSearchResult c_found, SearchRadius(sheet, SurfaceOptions(), o));
  const RadiusChoice& c = c_found.choice;
  ASSERT_GE(c.trials.size(), 3u);
  double best = -1;
  for (const RadiusTrial& t : c.trials) best = std::max(best, t.similarity);
  for (const RadiusTrial& t : c.trials) {
    if (t.radius == c.radius) EXPECT_EQ(t.similarity, best);
  }
  ExpectTheChosenSurface(sheet, c_found);
}

TEST(RadiusSearchTest, TargetGoalReturnsTheLargestRadiusReachingIt) {
  const SheetAnalysis sheet = Sheet();
  RadiusSearchOptions o;
  o.goal = RadiusGoal::kTargetSimilarity;
  o.target_similarity = 0.8;
  o.max_radius_voxels = 20;
  SM_ASSERT_OK_AND_ASSIGN(RadiusSearchResult c_found, SearchRadius(sheet, SurfaceOptions(), o));
  const RadiusChoice& c = c_found.choice;
  ASSERT_TRUE(c.target_reached);
  double chosen_sim = -1, fewest = 1e18;
  for (const RadiusTrial& t : c.trials) {
    if (t.radius == c.radius) {
      chosen_sim = t.similarity;
      fewest = t.triangles;
    }
  }
  EXPECT_GE(chosen_sim, 0.8);
  ExpectTheChosenSurface(sheet, c_found);
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
  SM_ASSERT_OK_AND_ASSIGN(RadiusSearchResult c_found, SearchRadius(sheet, SurfaceOptions(), o));
  const RadiusChoice& c = c_found.choice;
  EXPECT_FALSE(c.target_reached);
  EXPECT_GT(c.radius, 0);
}

TEST(RadiusSearchTest, TriangleGoalMeetsTheBudgetWithinFivePercent) {
  const SheetAnalysis sheet = Sheet();
  for (bool decimate : {false, true}) {
    for (uint64_t n : {60, 150, 400, 900}) {
      RadiusSearchOptions o;
      o.goal = RadiusGoal::kTriangles;
      o.triangles = n;
      o.decimate = decimate;
      SM_ASSERT_OK_AND_ASSIGN(RadiusSearchResult c_found, SearchRadius(sheet, SurfaceOptions(), o));
      const RadiusChoice& c = c_found.choice;
      EXPECT_TRUE(c.target_reached) << n << ": " << c.message;
      if (!decimate) EXPECT_EQ(c.decimated_to, 0u);
      ExpectTheChosenSurface(sheet, c_found);
      const SurfaceResult& built = c_found.surface;
      EXPECT_NEAR(double(built.mesh.num_faces()), double(n), 0.05 * n) << "r = " << c.radius;
      if (c.decimated_to > 0) {
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

TEST(RadiusSearchTest, TheMidSurfaceIsDecimatedToTheCountWithoutASearch) {
  const SheetAnalysis sheet = Sheet();
  SurfaceOptions s;
  s.method = SurfaceMethod::kMid;
  for (const uint64_t budget : {200u, 1000u}) {
    RadiusSearchOptions o;
    o.goal = RadiusGoal::kTriangles;
    o.triangles = budget;
    SM_ASSERT_OK_AND_ASSIGN(RadiusSearchResult found, SearchRadius(sheet, s, o));
    EXPECT_TRUE(found.choice.trials.empty());
    EXPECT_EQ(found.choice.decimated_to, budget);
    EXPECT_TRUE(found.choice.target_reached) << found.choice.message;
    EXPECT_NEAR(static_cast<double>(found.surface.mesh.num_faces()), budget, 0.05 * budget);
  }
}

TEST(RadiusSearchTest, TriangleGoalBelowTheOutlineOrBeyondTheFinestIsSaid) {
  const SheetAnalysis sheet = Sheet();
  RadiusSearchOptions o;
  o.goal = RadiusGoal::kTriangles;
  o.triangles = 0;
  EXPECT_THAT(SearchRadius(sheet, SurfaceOptions(), o),
              StatusIs(absl::StatusCode::kInvalidArgument, ::testing::HasSubstr("triangles = 0")));
  // Two triangles: fewer than the coarsest mesh (the largest r) has; the message names it.
  // (Decimating, the search says where the collapses stopped; the pipeline refuses that.)
  o.decimate = false;
  o.triangles = 2;
  o.max_radius_voxels = 12;
  SurfaceOptions coarsest;
  coarsest.scvd.radius_voxels = 12;
  SM_ASSERT_OK_AND_ASSIGN(SurfaceResult c, BuildSurface(sheet, coarsest));
  EXPECT_THAT(
      SearchRadius(sheet, SurfaceOptions(), o),
      StatusIs(absl::StatusCode::kInvalidArgument,
               ::testing::HasSubstr(absl::StrCat(c.mesh.num_faces(), " at the largest r"))));
  // More than the smallest r gives: the finest mesh, said not to reach it.
  o.triangles = 1000000;
  o.max_radius_voxels = 0;
  o.min_radius_voxels = 3;
  SM_ASSERT_OK_AND_ASSIGN(RadiusSearchResult fine_found, SearchRadius(sheet, SurfaceOptions(), o));
  const RadiusChoice& fine = fine_found.choice;
  EXPECT_FALSE(fine.target_reached);
  EXPECT_DOUBLE_EQ(fine.radius, 3);
  EXPECT_THAT(fine.message, ::testing::HasSubstr("1000000 triangles"));
  o.decimate = true;
  SM_ASSERT_OK_AND_ASSIGN(RadiusSearchResult finest_found,
                          SearchRadius(sheet, SurfaceOptions(), o));
  const RadiusChoice& finest = finest_found.choice;
  EXPECT_FALSE(finest.target_reached);
  EXPECT_THAT(finest.message, ::testing::HasSubstr("1000000 triangles"));
  o.triangles = 2;
  o.max_radius_voxels = 12;
  o.min_radius_voxels = 2;
  SM_ASSERT_OK_AND_ASSIGN(RadiusSearchResult stopped_found,
                          SearchRadius(sheet, SurfaceOptions(), o));
  const RadiusChoice& stopped = stopped_found.choice;
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
