#include "worker/pipeline/extract/extraction.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <map>

#include "common/orientation.h"
#include "tests/testing/shapes.h"
#include "tests/testing/shared_data.h"
#include "tests/testing/status_matchers.h"
#include "worker/pipeline/extract/piece_geology.h"
#include "worker/pipeline/phantom/phantom.h"
#include "worker/pipeline/voxel/sheet_input.h"
#include "worker/pipeline/voxel/thickness.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::BoxSet;
using ::sheetmesh::testing::StatusIs;

std::map<int32_t, uint64_t> Sizes(const LabelledVoxels& m) {
  std::map<int32_t, uint64_t> s;
  for (int32_t l : m.label) ++s[l];
  return s;
}

std::vector<PieceGeology> Geology(const LabelledVoxels& m) {
  return ComputePieceGeology(m, *ComputeThickness(m.set), TriangleMesh{}, Placement{});
}

TEST(ExtractionTest, PiercedPlateBecomesAHoledPlateAndTwoHalves) {
  const Dims d{64, 64, 64};
  const VoxelSet plate = BoxSet(d, {5, 5, 30}, {59, 59, 35});
  const VoxelSet pierce = BoxSet(d, {30, 20, 5}, {35, 44, 59});
  const VoxelSet input = Union(plate, pierce);
  SM_ASSERT_OK_AND_ASSIGN(ExtractionResult r, ExtractFeatures(input, {}));
  ASSERT_EQ(r.model.CountLabels(), 3u);
  // Piece 0 is the plate (largest): horizontal. Pieces 1 and 2 are the halves above and
  // below it: vertical.
  const std::vector<PieceGeology> g = Geology(r.model);
  EXPECT_NEAR(g[0].dip_degrees, 0.0, 1.0);
  EXPECT_NEAR(g[1].dip_degrees, 90.0, 1.0);
  EXPECT_NEAR(g[2].dip_degrees, 90.0, 1.0);
  EXPECT_NE(g[1].centroid.z > 32, g[2].centroid.z > 32) << "one half above the plate, one below";
  // The halves lie in one plane (B and C of Fig. 4): one sheet, apart from the plate's.
  EXPECT_EQ(g[1].sheet, g[2].sheet);
  EXPECT_NE(g[0].sheet, g[1].sheet);
  // Every step ran and reported.
  ASSERT_EQ(r.steps.size(), 5u);
  for (const ExtractionStep& s : r.steps) EXPECT_TRUE(s.ran) << s.name;
  EXPECT_GT(r.steps[2].removed, 0u) << "separation cut the crossing";
  EXPECT_GT(r.steps[4].added, 0u) << "recovery regrew from the image";
}

TEST(ExtractionTest, RecoveryClosesTheCutWithinTheImageOnly) {
  const Dims d{64, 64, 64};
  const VoxelSet plate = BoxSet(d, {5, 5, 30}, {59, 59, 35});
  const VoxelSet pierce = BoxSet(d, {30, 20, 5}, {35, 44, 59});
  ExtractionOptions with_recover;
  with_recover.refine = false;  // so that the image is the input itself
  ExtractionOptions no_recover = with_recover;
  no_recover.recover = false;
  SM_ASSERT_OK_AND_ASSIGN(ExtractionResult cut, ExtractFeatures(Union(plate, pierce), no_recover));
  SM_ASSERT_OK_AND_ASSIGN(ExtractionResult full,
                          ExtractFeatures(Union(plate, pierce), with_recover));
  EXPECT_TRUE(Difference(full.model.set, Union(plate, pierce)).empty());
  // Recovery gives back part of the plate's gap at the crossing.
  const VoxelSet gap = Difference(plate, cut.model.set);
  ASSERT_GT(gap.size(), 0u);
  EXPECT_LT(Difference(plate, full.model.set).size(), gap.size());
}

TEST(ExtractionTest, SpecksBelowMGoAndNothingLarger) {
  const Dims d{64, 64, 32};
  VoxelSet s = BoxSet(d, {4, 4, 10}, {60, 60, 14});   // a large sheet
  s = Union(s, BoxSet(d, {4, 4, 24}, {24, 24, 27}));  // a small sheet: 1200 voxels
  for (int k = 0; k < 5; ++k) s = Union(s, BoxSet(d, {8 * k + 4, 40, 28}, {8 * k + 6, 42, 30}));
  ExtractionOptions o;
  o.min_object_voxels = 100;
  o.separate = false;
  SM_ASSERT_OK_AND_ASSIGN(ExtractionResult r, ExtractFeatures(s, o));
  const auto sizes = Sizes(r.model);
  ASSERT_EQ(sizes.size(), 2u) << "the specks (8 voxels each) go, both sheets stay";
  EXPECT_EQ(r.model.set.size(), 56u * 56 * 4 + 20u * 20 * 3);
  EXPECT_EQ(r.steps[1].objects_before, 7u);
  EXPECT_EQ(r.steps[1].objects_after, 2u);
}

TEST(ExtractionTest, CoplanarFragmentsBelowMSurviveAsOneObject) {
  const Dims d{72, 48, 24};
  // Two fragments of 336 voxels each, 4 apart: each below M = 500, together above.
  const VoxelSet s =
      Union(BoxSet(d, {10, 10, 10}, {24, 22, 12}), BoxSet(d, {28, 10, 10}, {42, 22, 12}));
  ExtractionOptions o;
  o.min_object_voxels = 500;
  o.separate = false;
  o.remove_minor = false;
  o.refine = false;
  SM_ASSERT_OK_AND_ASSIGN(ExtractionResult r, ExtractFeatures(s, o));
  EXPECT_EQ(r.model.set.size(), s.size()) << "detection kept both fragments";
  EXPECT_EQ(r.model.CountLabels(), 1u) << "as one object";
  o.detect = false;
  EXPECT_THAT(ExtractFeatures(s, o),
              StatusIs(absl::StatusCode::kInvalidArgument, ::testing::HasSubstr("M = 500")));
}

TEST(ExtractionTest, AnEmptyOrAllMinorPhaseIsAnErrorNotAnEmptyModel) {
  const Dims d{32, 32, 32};
  EXPECT_THAT(ExtractFeatures(VoxelSet(d), {}),
              StatusIs(absl::StatusCode::kInvalidArgument, ::testing::HasSubstr("empty")));
  // Specks only: every object is below M.
  VoxelSet specks(d);
  for (int k = 0; k < 4; ++k)
    specks = Union(specks, BoxSet(d, {6 * k + 2, 4, 4}, {6 * k + 4, 6, 6}));
  EXPECT_THAT(ExtractFeatures(specks, {}),
              StatusIs(absl::StatusCode::kInvalidArgument, ::testing::HasSubstr("lower M")));
}

TEST(ExtractionTest, DpmJunctionGivesItsThreeSlabs) {
  SM_REQUIRE_SHARED_DATA("dpm_3fractures_100x100x100_u8.raw");
  SheetInput in;
  in.path = testing::SharedDataFile("dpm_3fractures_100x100x100_u8.raw");
  SM_ASSERT_OK_AND_ASSIGN(SheetPhase phase, LoadSheetPhase(in));
  SM_ASSERT_OK_AND_ASSIGN(ExtractionResult r, ExtractFeatures(phase.sheet, {}));
  ASSERT_EQ(r.model.CountLabels(), 3u);
  const std::vector<PieceGeology> g = Geology(r.model);
  for (const PieceGeology& p : g) EXPECT_GT(p.planarity, 0.95) << "piece " << p.piece;
  for (size_t i = 0; i < g.size(); ++i)
    for (size_t j = i + 1; j < g.size(); ++j)
      EXPECT_GT(AngleBetweenNormalsDegrees(g[i].normal, g[j].normal), 15.0) << i << "," << j;
}

TEST(ExtractionTest, PhantomSheetsAreRecoveredWithTheirNormals) {
  PhantomOptions o;
  o.dims = {128, 128, 128};
  o.num_sheets = 3;
  o.num_specks = 30;
  o.seed = 4;
  SM_ASSERT_OK_AND_ASSIGN(PhantomTruth truth, PlanPhantom(o));
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume vol, GeneratePhantomDense(&truth));
  VoxelSet::Builder b(o.dims);
  for (int z = 0; z < 128; ++z)
    for (int y = 0; y < 128; ++y)
      for (int x = 0; x < 128; ++x)
        if (vol.At(x, y, z) != 0) b.AddVoxel(x, y, z);
  SM_ASSERT_OK_AND_ASSIGN(ExtractionResult r, ExtractFeatures(std::move(b).Build(), {}));
  const std::vector<PieceGeology> geology = Geology(r.model);
  // Each piece belongs to the sheet whose band holds most of its voxels.
  std::vector<int> sheet_of(geology.size(), -1);
  std::vector<std::vector<int>> counts(geology.size(), std::vector<int>(truth.sheets.size(), 0));
  r.model.set.ForEachVoxel([&](uint64_t i, int32_t x, int32_t y, int32_t z) {
    for (size_t k = 0; k < truth.sheets.size(); ++k) {
      const PhantomSheet& s = truth.sheets[k];
      if (std::abs(Dot(Vec3(x, y, z) - s.center, s.normal)) <=
          s.aperture_max / 2 + s.undulation + 1) {
        ++counts[r.model.label[i]][k];
      }
    }
  });
  for (size_t p = 0; p < geology.size(); ++p) {
    sheet_of[p] =
        static_cast<int>(std::max_element(counts[p].begin(), counts[p].end()) - counts[p].begin());
  }
  for (size_t k = 0; k < truth.sheets.size(); ++k) {
    int largest = -1;
    for (size_t p = 0; p < geology.size(); ++p) {
      if (sheet_of[p] == static_cast<int>(k) &&
          (largest < 0 || geology[p].voxels > geology[largest].voxels)) {
        largest = static_cast<int>(p);
      }
    }
    ASSERT_GE(largest, 0) << "sheet " << k << " has no piece";
    EXPECT_LE(AngleBetweenNormalsDegrees(geology[largest].normal, truth.sheets[k].normal), 10.0)
        << "sheet " << k;
  }
}

}  // namespace
}  // namespace sheetmesh
