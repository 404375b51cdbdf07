#include "worker/pipeline/phantom/phantom.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "tests/testing/status_matchers.h"
#include "worker/pipeline/phantom/phantom_presets.h"
#include "worker/pipeline/voxel/components.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::StatusIs;

PhantomOptions Small() {
  PhantomOptions o;
  o.dims = {96, 80, 64};
  o.num_sheets = 3;
  o.num_specks = 20;
  o.seed = 11;
  return o;
}

TEST(PhantomTest, SameSeedGivesTheSameVolumeAndAnotherSeedDoesNot) {
  SM_ASSERT_OK_AND_ASSIGN(PhantomTruth t1, PlanPhantom(Small()));
  SM_ASSERT_OK_AND_ASSIGN(PhantomTruth t2, PlanPhantom(Small()));
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume a, GeneratePhantomDense(&t1));
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume b, GeneratePhantomDense(&t2));
  EXPECT_TRUE(a.data == b.data);
  PhantomOptions other = Small();
  other.seed = 12;
  SM_ASSERT_OK_AND_ASSIGN(PhantomTruth t3, PlanPhantom(other));
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume c, GeneratePhantomDense(&t3));
  EXPECT_FALSE(a.data == c.data);
}

TEST(PhantomTest, TruthCountsMatchTheVolumeAndSheetsAreThin) {
  SM_ASSERT_OK_AND_ASSIGN(PhantomTruth truth, PlanPhantom(Small()));
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume v, GeneratePhantomDense(&truth));
  uint64_t count = 0;
  for (std::byte b : v.data) count += b != std::byte{0};
  EXPECT_EQ(count, truth.sheet_voxels);
  ASSERT_EQ(truth.sheets.size(), 3u);
  for (const PhantomSheet& s : truth.sheets) {
    EXPECT_NEAR(Norm(s.normal), 1.0, 1e-12);
    EXPECT_NEAR(Dot(s.normal, s.u), 0.0, 1e-12);
    EXPECT_GE(s.normal.z, 0.0);
    EXPECT_GT(s.voxels, 1000u);
    EXPECT_GE(s.aperture_min, 1.0);
    EXPECT_LE(s.aperture_min, s.aperture_mean * 1.5);
  }
  const double fraction = double(count) / v.info.dims.num_voxels();
  EXPECT_GT(fraction, 0.01);
  EXPECT_LT(fraction, 0.2);
  const nlohmann::json j = nlohmann::json::parse(truth.ToJson());
  EXPECT_EQ(j["sheets"].size(), 3u);
  EXPECT_EQ(j["sheet_voxels"].get<uint64_t>(), count);
  EXPECT_TRUE(j["sheets"][0].contains("dip_degrees"));
}

TEST(PhantomTest, SpecksAreSmallSeparateComponents) {
  PhantomOptions o = Small();
  o.num_sheets = 0;
  o.num_specks = 15;
  SM_ASSERT_OK_AND_ASSIGN(PhantomTruth truth, PlanPhantom(o));
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume v, GeneratePhantomDense(&truth));
  std::vector<Index3> idx;
  for (int z = 0; z < o.dims.nz; ++z)
    for (int y = 0; y < o.dims.ny; ++y)
      for (int x = 0; x < o.dims.nx; ++x)
        if (v.At(x, y, z) != 0) idx.push_back({x, y, z});
  SM_ASSERT_OK_AND_ASSIGN(Components c,
                          LabelComponents(VoxelSet::FromIndices(o.dims, idx), Connectivity::k6));
  EXPECT_GE(c.count(), 10u);
  EXPECT_LE(c.sizes[0], 60u);
}

TEST(PhantomTest, InvalidOptionsAreInvalidArgument) {
  PhantomOptions o = Small();
  o.dims.nx = 0;
  EXPECT_THAT(PlanPhantom(o), StatusIs(absl::StatusCode::kInvalidArgument));
  o = Small();
  o.aperture_voxels = -1;
  EXPECT_THAT(PlanPhantom(o), StatusIs(absl::StatusCode::kInvalidArgument));
}

}  // namespace
}  // namespace sheetmesh

namespace sheetmesh {
namespace {

// The junction presets' known answer: two planes meeting at the angle asked for along the
// line the truth names (any orientation, by the seed); a T's stem stays on one side.
TEST(PhantomTest, JunctionsMeetAtTheirAngleAlongTheTruthsLine) {
  for (const double degrees : {15.0, 30.0, 60.0, 90.0}) {
    for (const bool t : {false, true}) {
      SCOPED_TRACE(::testing::Message() << degrees << (t ? " T" : " X"));
      absl::StatusOr<PhantomOptions> o = PhantomPreset("crossing");
      ASSERT_TRUE(o.ok());
      o->junction_degrees = degrees;
      o->junction_t = t;
      o->dims = {64, 64, 64};
      absl::StatusOr<PhantomTruth> truth = PlanPhantom(*o);
      ASSERT_TRUE(truth.ok());
      ASSERT_EQ(truth->sheets.size(), 2u);
      ASSERT_EQ(truth->junctions.size(), 1u);
      const PhantomJunction& j = truth->junctions[0];
      const Vec3 n0 = truth->sheets[0].normal, n1 = truth->sheets[1].normal;
      EXPECT_NEAR(Dot(j.direction, n0), 0, 1e-12);
      EXPECT_NEAR(Dot(j.direction, n1), 0, 1e-12);
      EXPECT_NEAR(std::acos(std::abs(Dot(n0, n1))) * 180 / M_PI, degrees, 1e-9);
      absl::StatusOr<DenseVolume> v = GeneratePhantomDense(&*truth);
      ASSERT_TRUE(v.ok());
      EXPECT_GT(truth->sheets[0].voxels, 1000u);
      EXPECT_GT(truth->sheets[1].voxels, 300u);
      // The stem of a T lies on the side of sheet 0 its v points to (within sheet 0's
      // thickness and a voxel): count its voxels far on the other side, away from sheet 0.
      if (!t) continue;
      const PhantomSheet& stem = truth->sheets[1];
      int wrong = 0;
      for (int z = 0; z < 64; ++z) {
        for (int y = 0; y < 64; ++y) {
          for (int x = 0; x < 64; ++x) {
            if (v->At(x, y, z) == 0) continue;
            const Vec3 d = Vec3(x, y, z) - stem.center;
            if (std::abs(Dot(d, stem.normal)) > 2) continue;  // not the stem's
            if (std::abs(Dot(d, n0)) <= 2) continue;          // sheet 0's
            if (Dot(d, stem.v) < -4) ++wrong;
          }
        }
      }
      EXPECT_EQ(wrong, 0);
    }
  }
}

}  // namespace
}  // namespace sheetmesh
