// The SCVD and dual triangles built brick by brick against the whole volume.
#include "worker/pipeline/surface/bricked_surface.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "tests/testing/preset_sheets.h"
#include "tests/testing/status_matchers.h"
#include "worker/pipeline/similarity/mesh_model.h"
#include "worker/pipeline/similarity/similarity.h"
#include "worker/pipeline/voxel/sheet_analysis.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::PresetSheets;
using ::sheetmesh::testing::StatusIs;
using ::testing::HasSubstr;

BrickedSurfaceOptions Whole(const Dims& d) {
  BrickedSurfaceOptions o;
  o.brick = d;
  o.halo = 0;
  return o;
}

double Similarity(const BrickedSurface& s, const VoxelSet& set) {
  absl::StatusOr<VoxelSet> model = VoxelizePrisms(s.mesh, set.dims(), PrismHeight::kVertex);
  EXPECT_TRUE(model.ok()) << model.status();
  return ScoreModel(*model, set).similarity;
}

struct Case {
  std::string preset;
  Dims dims;
  double r;
  Dims brick;
  Index3 grid_origin;
};

// Pass 2 in bricks, from the whole volume's generators, gives the whole volume's faces:
// bricks that cut through sheets, crossings and holes, cells over columns (thick slab, small
// r) and over voxels, a moved grid, bricks smaller than a cell.
TEST(BrickedSurfaceTest, TheBricksGiveTheWholeVolumesFacesFromTheSameGenerators) {
  const std::vector<Case> cases = {
      {"rough_network", {128, 128, 112}, 4, {40, 40, 40}, {}},
      {"thick_slab", {100, 100, 111}, 7, {32, 48, 40}, {}},
      {"thick_slab", {100, 100, 111}, 7, {32, 48, 40}, {13, 29, 7}},
      {"grazing_sheet", {140, 120, 80}, 10, {16, 16, 16}, {5, 0, 9}},  // brick < a cell
      {"vuggy_network", {128, 128, 112}, 2, {48, 48, 48}, {}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.preset + " r = " + std::to_string(c.r));
    const VoxelSet sheets = PresetSheets(c.preset, c.dims);
    SM_ASSERT_OK_AND_ASSIGN(SheetAnalysis a, AnalyzeSheet(sheets));
    const double t = a.thickness_stats.mean;
    const int t_max = *std::max_element(a.thickness.begin(), a.thickness.end());
    SurfaceOptions so;
    so.scvd.radius_voxels = c.r;
    so.scvd.lloyd_max_iter = 8;
    SM_ASSERT_OK_AND_ASSIGN(BrickedSurface whole,
                            BuildBrickedSurface(sheets, t, so, Whole(sheets.dims())));
    ASSERT_GT(whole.mesh.faces.size(), 50u);
    BrickedSurfaceOptions bo;
    bo.brick = c.brick;
    bo.halo = SurfaceHalo(c.r, t_max);
    bo.grid_origin = c.grid_origin;
    SM_ASSERT_OK_AND_ASSIGN(BrickedSurface bricked,
                            BuildBrickedSurface(sheets, t, so, bo, whole.generators));
    EXPECT_GT(bricked.bricks, 8u);
    EXPECT_EQ(bricked.disagreeing_vertices, 0u);
    EXPECT_EQ(bricked.seam_mismatches, 0u);
    EXPECT_EQ(bricked.retries, 0) << "the halo rule needs no second run here";
    EXPECT_EQ(FaceKeys(bricked), FaceKeys(whole));
    EXPECT_EQ(bricked.mesh.faces.size(), whole.mesh.faces.size()) << "no face twice";
    // A halo far too short, no retry: the bricks disagree at their seams and the check
    // says so.
    bo.halo = 3;
    bo.retries = 0;
    SM_ASSERT_OK_AND_ASSIGN(BrickedSurface short_halo,
                            BuildBrickedSurface(sheets, t, so, bo, whole.generators));
    EXPECT_NE(FaceKeys(short_halo), FaceKeys(whole));
    EXPECT_GT(short_halo.seam_mismatches, 0u);
    // With retries, pass 2 runs again with twice the halo until the seams agree.
    bo.retries = 6;
    SM_ASSERT_OK_AND_ASSIGN(BrickedSurface healed,
                            BuildBrickedSurface(sheets, t, so, bo, whole.generators));
    EXPECT_EQ(healed.seam_mismatches, 0u);
    EXPECT_GT(healed.retries, 0);
    EXPECT_EQ(FaceKeys(healed), FaceKeys(whole)) << "halo " << healed.halo;
  }
}

// Both passes in bricks: the generators near seams come from Lloyd steps on one brick's
// halo, so the surface is not the same, but as close to the whole volume's as another seed's
// (figures in bench/RESULTS.md).
TEST(BrickedSurfaceTest, BothPassesInBricksStayCloseToTheWholeVolume) {
  for (const std::string preset : {"rough_network", "grazing_sheet"}) {
    SCOPED_TRACE(preset);
    const VoxelSet sheets = PresetSheets(preset, {128, 128, 112});
    SM_ASSERT_OK_AND_ASSIGN(SheetAnalysis a, AnalyzeSheet(sheets));
    const double t = a.thickness_stats.mean;
    const int t_max = *std::max_element(a.thickness.begin(), a.thickness.end());
    SurfaceOptions so;
    so.scvd.radius_voxels = 4;
    so.scvd.lloyd_max_iter = 8;
    SM_ASSERT_OK_AND_ASSIGN(BrickedSurface whole,
                            BuildBrickedSurface(sheets, t, so, Whole(sheets.dims())));
    BrickedSurfaceOptions bo;
    bo.brick = {40, 40, 40};
    bo.halo = SurfaceHalo(4, t_max);
    SM_ASSERT_OK_AND_ASSIGN(BrickedSurface bricked, BuildBrickedSurface(sheets, t, so, bo));
    EXPECT_EQ(bricked.disagreeing_vertices, 0u);
    EXPECT_EQ(bricked.seam_mismatches, 0u);
    const double faces = double(whole.mesh.faces.size());
    EXPECT_NEAR(double(bricked.mesh.faces.size()), faces, 0.03 * faces);
    EXPECT_NEAR(Similarity(bricked, sheets), Similarity(whole, sheets), 0.01);
    EXPECT_GT(bricked.bricks, 8u);
  }
}

TEST(BrickedSurfaceTest, ABadGridIsInvalidArgumentNamingFieldAndValue) {
  BrickedSurfaceOptions bo;
  bo.brick = {64, 0, 64};
  EXPECT_THAT(SurfaceBrickGrid({100, 100, 100}, bo),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("bricks.brick (64, 0, 64)")));
  bo.brick = {64, 64, 64};
  bo.halo = -3;
  EXPECT_THAT(SurfaceBrickGrid({100, 100, 100}, bo),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("bricks.halo -3")));
  // The grid's lines pass through its origin; every voxel is in exactly one core.
  bo.halo = 5;
  bo.grid_origin = {70, -10, 164};
  SM_ASSERT_OK_AND_ASSIGN(std::vector<BrickBox> grid, SurfaceBrickGrid({100, 90, 80}, bo));
  uint64_t voxels = 0;
  for (const BrickBox& b : grid) {
    voxels += uint64_t(b.core.nx) * b.core.ny * b.core.nz;
    EXPECT_TRUE(b.core_lo.x == 0 || (b.core_lo.x - 70) % 64 == 0);
    EXPECT_TRUE(b.core_lo.y == 0 || (b.core_lo.y + 10) % 64 == 0);
    EXPECT_TRUE(b.core_lo.z == 0 || (b.core_lo.z - 164) % 64 == 0);
    EXPECT_TRUE(b.InBox(b.core_lo));
  }
  EXPECT_EQ(voxels, 100u * 90 * 80);
}

}  // namespace
}  // namespace sheetmesh
