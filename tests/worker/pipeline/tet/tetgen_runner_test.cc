#include "worker/pipeline/tet/tetgen_runner.h"

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
#include "worker/pipeline/tet/volume_mesher.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::Append;
using ::sheetmesh::testing::ClosestPair;
using ::sheetmesh::testing::DistanceToSheets;
using ::sheetmesh::testing::Square;
using ::sheetmesh::testing::StatusIs;
using ::sheetmesh::testing::TempDir;
using ::testing::HasSubstr;

// A stand-in TetGen: a script that behaves badly.
std::string FakeTetgen(const TempDir& tmp, const std::string& body) {
  const std::string path = tmp.File("fake-tetgen");
  EXPECT_TRUE(WriteFileAtomically(path, "#!/bin/sh\n" + body + "\n").ok());
  std::filesystem::permissions(path, std::filesystem::perms::owner_all);
  return path;
}

TEST(TetgenRunnerTest, TetgenSwitchesLeaveOutTetgensOwnVertexInsertion) {
  // -O2/3: TetGen's flips and smoothing only; its vertex insertion/deletion (operation 4)
  // listed facet faces no tetrahedron had.
  // -Y by default: TetGen adds no point on a facet.
  EXPECT_EQ(TetgenSwitches({}), "-pzQq1.5/10O2/3Y");
  TetgenOptions o;
  o.max_radius_edge_ratio = 0;
  o.max_volume = 5;
  o.steiner_on_sheets = true;
  EXPECT_EQ(TetgenSwitches(o), "-pzQa5O2/3");
}

TEST(TetgenRunnerTest, TetgenThatHangsIsKilledAtTheTimeLimit) {
  TempDir tmp;
  VolumeMeshOptions o;
  o.tetgen.program = FakeTetgen(tmp, "sleep 30");
  o.tetgen.time_limit_seconds = 0.5;
  EXPECT_THAT(BuildVolumeMesh(Square(4, 15, 10, 2), {20, 20, 20}, {}, o),
              StatusIs(absl::StatusCode::kDeadlineExceeded,
                       HasSubstr("tet.time_limit_seconds = 0.5 s while TetGen ran")));
}

TEST(TetgenRunnerTest, TetgenThatIsKilledOrFailsGivesTheDocumentedErrors) {
  TempDir tmp;
  VolumeMeshOptions o;
  o.tetgen.program = FakeTetgen(tmp, "echo dying; kill -9 $$");
  EXPECT_THAT(BuildVolumeMesh(Square(4, 15, 10, 2), {20, 20, 20}, {}, o),
              StatusIs(absl::StatusCode::kInternal,
                       ::testing::AllOf(HasSubstr("signal 9"), HasSubstr("dying"))));
  o.tetgen.program = FakeTetgen(tmp, "echo 'Error: self-intersection'; exit 3");
  EXPECT_THAT(BuildVolumeMesh(Square(4, 15, 10, 2), {20, 20, 20}, {}, o),
              StatusIs(absl::StatusCode::kInternal,
                       ::testing::AllOf(HasSubstr("code 3"), HasSubstr("self-intersection"))));
  o.tetgen.program = "no-such-tetgen-program";
  EXPECT_THAT(BuildVolumeMesh(Square(4, 15, 10, 2), {20, 20, 20}, {}, o),
              StatusIs(absl::StatusCode::kNotFound));
}

// TetGen that crashes on a PLC under some switches (as it segfaults recovering a sheet
// triangle whole under -Y) runs again with others; what failed is in the report, and the
// PLC is kept for a bug report.
TEST(TetgenRunnerTest, ATetgenCrashIsRecoveredWithOtherSwitchesAndReported) {
  TempDir tmp;
  VolumeMeshOptions o;
  o.tetgen.failed_plc_path = tmp.File("failed.poly");
  // Crashes whenever asked to refine (-q) and to add no point on the facets (-Y).
  o.tetgen.program =
      FakeTetgen(tmp, "case \"$1\" in *q*Y*) kill -11 $$;; esac\nexec tetgen \"$@\"");
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult r,
                          BuildVolumeMesh(Square(4, 15, 10, 2), {20, 20, 20}, {}, o));
  // The same switches first run again twice with the lattice seeds moved (kSeedMoves), then
  // with the sheet vertices moved.
  ASSERT_EQ(r.tetgen_recovery.size(), 4u);
  EXPECT_THAT(r.tetgen_recovery[0], HasSubstr("-pzQq1.5/10O2/3Y: TetGen crashed with signal 11"));
  EXPECT_THAT(r.tetgen_recovery[1],
              HasSubstr("-pzQq1.5/10O2/3Y (lattice seeds moved): TetGen crashed with signal 11"));
  EXPECT_THAT(r.tetgen_recovery[3],
              HasSubstr("-pzQq1.5/10O2/3Y (sheet vertices moved): TetGen crashed with signal 11"));
  EXPECT_EQ(r.seed_moves, 3u);
  EXPECT_EQ(r.tetgen_switches, "-pzQO2/3Y");
  EXPECT_EQ(r.conformity.conforming, r.conformity.sheet_triangles);
  EXPECT_TRUE(std::filesystem::exists(tmp.File("failed.poly")));
  // Crashing under -Y whatever the rest: TetGen may then add points on the sheets.
  o.tetgen.program = FakeTetgen(tmp, "case \"$1\" in *Y*) kill -11 $$;; esac\nexec tetgen \"$@\"");
  SM_ASSERT_OK_AND_ASSIGN(r, BuildVolumeMesh(Square(4, 15, 10, 2), {20, 20, 20}, {}, o));
  EXPECT_EQ(r.tetgen_recovery.size(), 8u);
  EXPECT_EQ(r.tetgen_switches, "-pzQO2/3");
  EXPECT_EQ(r.conformity.conforming, r.conformity.sheet_triangles);
  // Crashing whatever: the last error is returned.
  o.tetgen.program = FakeTetgen(tmp, "kill -11 $$");
  EXPECT_THAT(BuildVolumeMesh(Square(4, 15, 10, 2), {20, 20, 20}, {}, o),
              StatusIs(absl::StatusCode::kInternal, HasSubstr("signal 11")));
}

// TetGen 1.5 crashes on some PLCs and meshes them with the lattice seeds a thousandth of a
// voxel elsewhere: a crash is first tried again with the same switches and the seeds moved.
TEST(TetgenRunnerTest, ACrashThatTheSeedsMovedAvoidKeepsTheSwitches) {
  TempDir tmp;
  VolumeMeshOptions o;
  const std::string once = tmp.File("crashed_once");
  o.tetgen.program = FakeTetgen(tmp, "if [ ! -e " + once + " ]; then touch " + once +
                                         "; kill -11 $$; fi\nexec tetgen \"$@\"");
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult r,
                          BuildVolumeMesh(Square(4, 15, 10, 2), {20, 20, 20}, {}, o));
  ASSERT_EQ(r.tetgen_recovery.size(), 1u);
  EXPECT_THAT(r.tetgen_recovery[0], HasSubstr("-pzQq1.5/10O2/3Y: TetGen crashed with signal 11"));
  EXPECT_EQ(r.seed_moves, 1u);
  EXPECT_EQ(r.tetgen_switches, "-pzQq1.5/10O2/3Y");
  EXPECT_EQ(r.conformity.conforming, r.conformity.sheet_triangles);
}

TEST(TetgenRunnerTest, CancellationKillsTetgen) {
  TempDir tmp;
  VolumeMeshOptions o;
  o.tetgen.program = FakeTetgen(tmp, "sleep 30");
  struct Stop : ProgressObserver {
    bool OnProgress(absl::string_view, double, absl::string_view) override { return false; }
  } stop;
  EXPECT_THAT(BuildVolumeMesh(Square(4, 15, 10, 2), {20, 20, 20}, {}, o, Progress(&stop, "volume")),
              StatusIs(absl::StatusCode::kCancelled));
}

TEST(TetgenRunnerTest, TetgensOwnCheckNamesTheFacetsThatCutThroughEachOther) {
  // A clean PLC of one square sheet, then a triangle laid through it by hand (past every
  // check of BuildPlc): TetGen's exact check names that pair, facets counted from 0.
  SM_ASSERT_OK_AND_ASSIGN(Plc plc, BuildPlc(Square(4, 16, 10, 2), {20, 20, 20}, {}));
  SM_ASSERT_OK_AND_ASSIGN(auto none, FindFacetIntersections(plc, {}));
  EXPECT_TRUE(none.empty());
  const uint32_t base = static_cast<uint32_t>(plc.vertices.size());
  plc.vertices.push_back({7, 7, 8});
  plc.vertices.push_back({8, 7, 12});
  plc.vertices.push_back({7.5, 8, 12});
  const uint32_t t = static_cast<uint32_t>(plc.sheet_triangles.size());
  plc.sheet_triangles.push_back({base, base + 1, base + 2});
  plc.sheet_piece.push_back(1);
  plc.sheet_thickness.push_back(1);
  plc.facets.push_back({{{base, base + 1, base + 2}}, kFirstSheetMarker + static_cast<int32_t>(t)});
  SM_ASSERT_OK_AND_ASSIGN(auto pairs, FindFacetIntersections(plc, {}));
  ASSERT_FALSE(pairs.empty());
  const uint32_t added = static_cast<uint32_t>(plc.facets.size() - 1);
  for (const auto& [a, b] : pairs) {
    EXPECT_LT(a, b);
    EXPECT_EQ(b, added);
    EXPECT_GE(a, 6u);  // a sheet facet, not the box's
  }
  // Removing the added triangle leaves the PLC as clean as it was, its markers in order.
  std::vector<uint8_t> drop(plc.sheet_triangles.size(), 0);
  drop[t] = 1;
  EXPECT_EQ(DropSheetTriangles(drop, &plc), 1u);
  EXPECT_EQ(plc.sheet_triangles.size(), t);
  for (size_t k = 0; k < plc.sheet_triangles.size(); ++k) {
    EXPECT_EQ(plc.facets[6 + k].marker, kFirstSheetMarker + static_cast<int32_t>(k));
  }
  SM_ASSERT_OK_AND_ASSIGN(auto after, FindFacetIntersections(plc, {}));
  EXPECT_TRUE(after.empty());
}

TEST(TetgenRunnerTest, AMissingTetgenIsNotFoundForTheCheckToo) {
  TetgenOptions o;
  o.program = "/nonexistent/tetgen";
  SM_ASSERT_OK_AND_ASSIGN(Plc plc, BuildPlc(Square(4, 16, 10, 2), {20, 20, 20}, {}));
  EXPECT_THAT(FindFacetIntersections(plc, o), StatusIs(absl::StatusCode::kNotFound));
}

}  // namespace
}  // namespace sheetmesh
