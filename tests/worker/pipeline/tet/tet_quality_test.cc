#include "worker/pipeline/tet/tet_quality.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <set>

#include "common/file_util.h"
#include "tests/testing/status_matchers.h"
#include "tests/testing/temp_dir.h"
#include "tests/worker/pipeline/tet/tet_test_shapes.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/tetgen_runner.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::Append;
using ::sheetmesh::testing::ClosestPair;
using ::sheetmesh::testing::DistanceToSheets;
using ::sheetmesh::testing::Square;
using ::sheetmesh::testing::StatusIs;
using ::sheetmesh::testing::TempDir;
using ::testing::HasSubstr;

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
