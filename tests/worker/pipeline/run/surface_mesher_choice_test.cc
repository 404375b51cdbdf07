// surface.mesher auto: the SCVD's surface and the mid-surface both built and scored, the
// mid-surface (its junctions at the rock's angles) kept unless it scores clearly below.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/progress.h"
#include "tests/testing/shapes.h"
#include "tests/testing/status_matchers.h"
#include "worker/pipeline/run/pipeline.h"
#include "worker/pipeline/voxel/sheet_input.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::ShapeSet;

SheetPhase Phase(VoxelSet set) {
  SheetPhase phase;
  phase.info.dims = set.dims();
  phase.sheet = std::move(set);
  return phase;
}

PipelineOptions AutoMesher(double r) {
  PipelineOptions o;
  o.extract = false;
  o.surface.method = SurfaceMethod::kAuto;
  o.surface.scvd.radius_voxels = r;
  o.representation.mode = RepresentationMode::kSheet;
  o.score.hausdorff = false;
  o.score.grid_rates.clear();
  return o;
}

// The stages a run reports, each once in order.
struct Stages : ProgressObserver {
  bool OnProgress(absl::string_view stage, double, absl::string_view) override {
    if (seen.empty() || seen.back() != stage) seen.emplace_back(stage);
    return true;
  }
  std::vector<std::string> seen;
};

TEST(SurfaceMesherChoiceTest, TwoPlanesCrossingKeepTheMidSurface) {
  // Two 3-voxel planes crossing at 60 degrees along a line across the box's axes: the
  // mid-surface meets on the true line and scores at least the SCVD's.
  const int n = 64;
  const Vec3 u = Normalized(Vec3(0.15, -0.8, 0.55));
  const Vec3 a = Normalized(Cross(u, Vec3(0, 0, 1)));
  const Vec3 b = Normalized(a * std::cos(2 * M_PI / 3) + Cross(u, a) * std::sin(2 * M_PI / 3));
  const Vec3 c(n / 2.0 - 0.5, n / 2.0 - 0.5, n / 2.0 - 0.5);
  VoxelSet set = ShapeSet(Dims{n, n, n}, [=](double x, double y, double z) {
    const Vec3 p = Vec3(x, y, z) - c;
    return std::abs(Dot(p, a)) <= 1.5 || std::abs(Dot(p, b)) <= 1.5;
  });
  Stages stages;
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport r,
                          RunPipelineOnPhase(AutoMesher(4), Phase(set), Progress(&stages, "")));
  // Without the extraction the mid-surface's separation runs as stages of its own, planned.
  EXPECT_EQ(stages.seen, PlannedStages(AutoMesher(4)));
  ASSERT_TRUE(r.surface->mesher_choice.has_value());
  const MesherChoiceStats& choice = *r.surface->mesher_choice;
  EXPECT_TRUE(choice.kept_mid);
  EXPECT_GE(choice.mid_similarity, choice.scvd_similarity - choice.margin);
  EXPECT_GT(choice.mid_similarity, 0.95);
  // The run's score is the kept surface's.
  EXPECT_NEAR(r.similarity->score.similarity, choice.mid_similarity, 1e-12);
  const nlohmann::json j = nlohmann::json::parse(r.ToJson());
  EXPECT_EQ(j["surface"]["mesher_choice"]["kept"], "midsurface");
}

TEST(SurfaceMesherChoiceTest, AClosedShellKeepsTheScvd) {
  // A spherical shell is a height field along no axis: the mid-surface cuts it into caps
  // and scores far below the SCVD's surface, which is kept with its own pieces.
  const int n = 48;
  const double m = (n - 1) / 2.0;
  VoxelSet set = ShapeSet(Dims{n, n, n}, [=](double x, double y, double z) {
    const double d = std::sqrt((x - m) * (x - m) + (y - m) * (y - m) + (z - m) * (z - m));
    return d >= 14 && d <= 17;
  });
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport r, RunPipelineOnPhase(AutoMesher(3), Phase(set)));
  ASSERT_TRUE(r.surface->mesher_choice.has_value());
  const MesherChoiceStats& choice = *r.surface->mesher_choice;
  EXPECT_FALSE(choice.kept_mid);
  EXPECT_GT(choice.scvd_similarity, choice.mid_similarity + choice.margin);
  EXPECT_NEAR(r.similarity->score.similarity, choice.scvd_similarity, 1e-12);
  // The SCVD's pieces: the shell is one component, one piece.
  EXPECT_EQ(r.surface->topology.connected_parts, 1u);
  const nlohmann::json j = nlohmann::json::parse(r.ToJson());
  EXPECT_EQ(j["surface"]["mesher_choice"]["kept"], "scvd");
}

}  // namespace
}  // namespace sheetmesh
