// Where TetGen crashes on a PLC whatever its lattice seeds, the sheet vertices are moved a
// millionth of a voxel and it meshes the sheets whole: DPM's junction at r = 3, a real
// scan, reaches 10 degrees where the fallback that lets TetGen split the sheets left 8.8.
// Where a mesh stays under the aim and its input does not force that, it is made again from
// moved lattice seeds and the better of the two kept.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "tests/testing/shared_data.h"
#include "tests/testing/status_matchers.h"
#include "tests/testing/temp_dir.h"
#include "tests/worker/pipeline/tet/tet_test_shapes.h"
#include "worker/pipeline/run/pipeline.h"
#include "worker/pipeline/tet/plc.h"
#include "worker/pipeline/tet/volume_mesher.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::Square;
using ::sheetmesh::testing::TempDir;

TEST(TetgenRecoveryTest, SheetVerticesMoveWithinHalfTheAmountAndStayOnTheBoxFaces) {
  Plc plc;
  plc.box_lo = {-0.5, -0.5, -0.5};
  plc.box_hi = {9.5, 9.5, 9.5};
  plc.voxel_length = 1;
  // A sheet triangle with a corner on the face x = -0.5 and one on the edge y = z = 9.5,
  // and a seed on no facet.
  plc.vertices = {{-0.5, 3, 3}, {4, 9.5, 9.5}, {5, 5, 2}, {2, 2, 2}};
  plc.sheet_triangles = {{0, 1, 2}};
  Plc moved = plc;
  JitterSheetVertices(1, 1e-6, &moved);
  EXPECT_EQ(moved.vertices[0].x, -0.5);
  EXPECT_EQ(moved.vertices[1].y, 9.5);
  EXPECT_EQ(moved.vertices[1].z, 9.5);
  EXPECT_EQ(moved.vertices[3], plc.vertices[3]);
  int changed = 0;
  for (int v = 0; v < 3; ++v) {
    for (int k = 0; k < 3; ++k) {
      const double d = std::abs(moved.vertices[v][k] - plc.vertices[v][k]);
      EXPECT_LE(d, 0.5e-6);
      changed += d > 0;
    }
  }
  EXPECT_EQ(changed, 6);  // every coordinate off the box moved
  // The same salt, the same offsets; another salt, others.
  Plc again = plc, other = plc;
  JitterSheetVertices(1, 1e-6, &again);
  JitterSheetVertices(2, 1e-6, &other);
  EXPECT_EQ(again.vertices, moved.vertices);
  EXPECT_NE(other.vertices, moved.vertices);
}

TEST(TetgenRecoveryTest, DpmJunctionAtRadiusThreeIsMeshedWithItsSheetsWholeAtTenDegrees) {
  SM_REQUIRE_SHARED_DATA("dpm_3fractures_100x100x100_u8.raw");
  TempDir tmp;
  PipelineOptions o;
  o.input.path = testing::SharedDataFile("dpm_3fractures_100x100x100_u8.raw");
  o.input.selection = PhaseSelection::Labels({255});
  o.surface.scvd.radius_voxels = 3;
  o.extract = false;
  o.score.hausdorff = false;
  o.score.grid_rates.clear();
  o.volume_mesh = true;
  o.output.dir = tmp.File("out");
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport r, RunPipeline(o));
  ASSERT_TRUE(r.volume_mesh.has_value());
  const VolumeMeshStats& m = *r.volume_mesh;
  // TetGen kept the sheet triangles whole (-Y), after whatever it took.
  EXPECT_THAT(m.tetgen_switches, ::testing::HasSubstr("Y"));
  EXPECT_GE(m.quality.min_dihedral.min, 10.0);
  EXPECT_FALSE(m.angle_warning.has_value());
  EXPECT_EQ(m.conformity.conforming, m.conformity.sheet_triangles);
}

TEST(VolumeMeshSecondTryTest, AMeshUnderTheAimTheInputDoesNotForceIsMadeAgainAndTheBetterKept) {
  // A flat sheet (the input's narrowest wedge 90 degrees) and an aim no mesh of this
  // lattice reaches: TetGen, the improvement and the sliver rounds run again from the
  // lattice seeds moved, and the mesh written is the better of the two.
  VolumeMeshOptions o;
  o.tetgen.min_dihedral_degrees = 40;
  o.tetgen.max_radius_edge_ratio = 0;  // TetGen's own refinement to 40 degrees would not end
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult r,
                          BuildVolumeMesh(Square(4, 15, 10, 4), {20, 20, 20}, {}, o));
  ASSERT_TRUE(r.second_try.tried);
  EXPECT_TRUE(r.second_try.stopped.empty()) << r.second_try.stopped;
  EXPECT_GT(r.second_try.min_dihedral_first, 0);
  EXPECT_GT(r.second_try.min_dihedral_second, 0);
  EXPECT_LT(r.quality.min_dihedral.min, 40);
  EXPECT_NEAR(
      r.quality.min_dihedral.min,
      r.second_try.kept ? r.second_try.min_dihedral_second : r.second_try.min_dihedral_first, 1e-9);
  EXPECT_GE(r.quality.min_dihedral.min,
            std::max(r.second_try.min_dihedral_first, r.second_try.min_dihedral_second) - 0.1);
  EXPECT_NEAR(r.quality.volume, r.box_volume, 1e-9 * r.box_volume);
  EXPECT_EQ(r.conformity.conforming, r.conformity.sheet_triangles);
  // At the default aim the mesh reaches it the first time: no second try.
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult d,
                          BuildVolumeMesh(Square(4, 15, 10, 4), {20, 20, 20}, {}, {}));
  EXPECT_GE(d.quality.min_dihedral.min, 10);
  EXPECT_FALSE(d.second_try.tried);
}

}  // namespace
}  // namespace sheetmesh
