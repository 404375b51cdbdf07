// Apertures from missing attenuation against the apertures the phantom was drawn with.
#include "worker/pipeline/surface/grey_apertures.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/testing/grey_phantoms.h"
#include "tests/testing/status_matchers.h"
#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {
namespace {

using testing::GreyPhantomOptions;
using testing::GreySheet;

// A grid of triangles on the sheet's mid-plane, `cell` voxels wide, inside the box away
// from the void band, with a face thickness of 2 voxels (what a detected band gives).
TriangleMesh PlaneMesh(const GreySheet& s, double half, double cell) {
  TriangleMesh m;
  const Vec3 u = Normalized(s.along), v = Normalized(Cross(s.normal, u));
  const int n = static_cast<int>(2 * half / cell);
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      m.vertices.push_back(s.center + u * (-half + i * cell) + v * (-half + j * cell));
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      m.faces.push_back({a, b, d});
      m.faces.push_back({a, d, c});
    }
  m.face_thickness_voxels.assign(m.faces.size(), 2.f);
  return m;
}

GreySheet Tilted(double aperture) {
  GreySheet s;
  s.center = {30, 24, 24};
  s.normal = Normalized(Vec3(0.25, 0.35, 1));
  s.along = Normalized(Cross(s.normal, Vec3(0, 1, 0)));
  s.aperture = aperture;
  return s;
}

// Mean aperture within 10% (or 0.1 voxel) of the truth from 0.5 voxel up, within 25% at
// 0.2, over point spreads of 0.5-1.5 voxels and contrast-to-noise 5-20; the rock's level
// is the one each face finds at its window's ends.
TEST(GreyAperturesTest, MeanApertureMatchesTheTruthUnderBlurAndNoise) {
  for (double a : {0.2, 0.5, 1.0, 2.0, 4.0}) {
    for (double sigma : {0.5, 1.0, 1.5}) {
      for (double cnr : {5.0, 20.0}) {
        GreyPhantomOptions o;
        o.dims = {64, 64, 64};  // a sheet of 36 x 36 voxels measured: the mean's noise
        o.sheets = {Tilted(a)};
        o.sheets[0].center = {38, 32, 32};
        o.psf_sigma = sigma;
        o.cnr = cnr;
        o.seed = 7;
        const GreyVolume g = testing::MakeGreyPhantom(o);
        // The levels given, as a calibrated scan has them (MeasureGreyLevels is
        // GreyLevelsTest's; at CNR 5 and a point spread of 1.5 the void's peak can drown in
        // the partial voxels of its own edge, and the run then says so and counts voxels).
        SM_ASSERT_OK_AND_ASSIGN(GreyLevels levels, MeasureGreyLevels(g, 40.0, 200.0, "g"));
        TriangleMesh m = PlaneMesh(o.sheets[0], 18, 3);
        GreyApertureOptions ao;
        ao.psf_sigma_voxels = sigma;
        SM_ASSERT_OK_AND_ASSIGN(GreyApertureStats st, SetGreyApertures(&m, g, levels, ao));
        ASSERT_TRUE(st.measured) << "aperture " << a << ", sigma " << sigma << ", cnr " << cnr
                                 << ": " << levels.problem;
        const double tolerance = a < 0.5 ? 0.25 * a : std::max(0.1 * a, 0.1);
        EXPECT_NEAR(st.mean_voxels, a, tolerance)
            << "aperture " << a << ", sigma " << sigma << ", cnr " << cnr;
        EXPECT_DOUBLE_EQ(st.counted_mean_voxels, 2.0);
      }
    }
  }
}

TEST(GreyAperturesTest, AnApertureVaryingAlongTheSheetIsFollowedFaceByFace) {
  GreyPhantomOptions o;
  GreySheet s = Tilted(1.65);
  s.aperture_slope = 2.7 / 26;  // 0.3 to 3 voxels over 26 voxels
  o.sheets = {s};
  o.cnr = 10;
  const GreyVolume g = testing::MakeGreyPhantom(o);
  SM_ASSERT_OK_AND_ASSIGN(GreyLevels levels, MeasureGreyLevels(g, {}, {}, "g"));
  TriangleMesh m = PlaneMesh(s, 13, 2);
  SM_ASSERT_OK_AND_ASSIGN(GreyApertureStats st, SetGreyApertures(&m, g, levels, {}));
  double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  const double n = m.faces.size();
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const Triangle t = Corners(m, f);
    const double truth = s.Aperture((t[0] + t[1] + t[2]) * (1.0 / 3));
    const double got = m.face_aperture_voxels[f];
    sx += truth;
    sy += got;
    sxx += truth * truth;
    syy += got * got;
    sxy += truth * got;
  }
  const double r = (sxy - sx * sy / n) / std::sqrt((sxx - sx * sx / n) * (syy - sy * sy / n));
  EXPECT_GE(r, 0.95);
}

TEST(GreyAperturesTest, LevelsThatAllowNoApertureChangeNothingAndSayWhy) {
  GreyPhantomOptions o;
  o.sheets = {Tilted(1)};
  o.void_band = 0;
  const GreyVolume g = testing::MakeGreyPhantom(o);
  SM_ASSERT_OK_AND_ASSIGN(GreyLevels levels, MeasureGreyLevels(g, {}, {}, "g"));
  TriangleMesh m = PlaneMesh(o.sheets[0], 10, 3);
  SM_ASSERT_OK_AND_ASSIGN(GreyApertureStats st, SetGreyApertures(&m, g, levels, {}));
  EXPECT_FALSE(st.measured);
  EXPECT_TRUE(m.face_aperture_voxels.empty());
  GreyApertureOptions bad;
  bad.psf_sigma_voxels = 0;
  EXPECT_THAT(SetGreyApertures(&m, g, levels, bad),
              testing::StatusIs(absl::StatusCode::kInvalidArgument,
                                ::testing::HasSubstr("grey.psf_sigma = 0")));
}

}  // namespace
}  // namespace sheetmesh
