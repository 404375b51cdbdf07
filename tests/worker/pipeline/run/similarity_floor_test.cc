// The grid floor (the paper's Table 2 baselines) and the warning for a surface under it.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "common/file_util.h"
#include "tests/testing/preset_sheets.h"
#include "tests/testing/status_matchers.h"
#include "tests/testing/temp_dir.h"
#include "worker/pipeline/phantom/phantom.h"
#include "worker/pipeline/phantom/phantom_presets.h"
#include "worker/pipeline/run/pipeline.h"
#include "worker/pipeline/volume/raw_io.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::PresetRawFile;
using ::sheetmesh::testing::TempDir;

TEST(SimilarityFloorTest, ASurfaceUnderEveryGridModelWarnsNamingTheFloor) {
  // The floor is the lowest of the grid models asked for; a mesh under it warns, in the
  // CLI's line and in the report (similarity.floor_warning), one at or over it does not.
  SimilarityReport sim;
  sim.grid = {{2, 0.95, 140000}, {3, 0.93, 42772}, {4, 0.91, 17500}};
  sim.score.similarity = 0.90;
  const std::optional<std::string> w = sim.FloorWarning();
  ASSERT_TRUE(w.has_value());
  EXPECT_THAT(*w, ::testing::HasSubstr("similarity 0.9000 is under the grid model's 0.9100"));
  EXPECT_THAT(*w, ::testing::HasSubstr("every 4th voxel kept, 17500 cells"));
  const nlohmann::json j = sim.Fields();
  ASSERT_TRUE(j.contains("floor_warning"));
  EXPECT_EQ(j["floor_warning"]["text"], *w);
  EXPECT_EQ(j["floor_warning"]["rate"], 4);
  EXPECT_DOUBLE_EQ(j["floor_warning"]["floor"].get<double>(), 0.91);
  sim.score.similarity = 0.91;  // at the floor: none
  EXPECT_FALSE(sim.FloorWarning().has_value());
  EXPECT_FALSE(sim.Fields().contains("floor_warning"));
  sim.score.similarity = 0.2;  // no grid model asked for: no floor
  sim.grid.clear();
  EXPECT_FALSE(sim.FloorWarning().has_value());
}

TEST(SimilarityFloorTest, AThickSlabMeshedAsASheetScoresUnderTheGridFloorAndSaysSo) {
  // The thick_slab preset (one slab 30-50 voxels thick) forced to one layer at r = 3
  // scores about 0.87, under the coarsest grid model's 0.91: the report says so.
  TempDir tmp;
  const std::string path = PresetRawFile(tmp, "thick_slab");
  PipelineOptions o;
  o.input.path = path;
  o.output.dir = tmp.File("out");
  o.extract = false;
  o.surface.scvd.radius_voxels = 3;
  o.representation.mode = RepresentationMode::kSheet;
  o.score.hausdorff = false;
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport r, RunPipeline(o));
  ASSERT_EQ(r.similarity->grid.size(), 3u);
  EXPECT_LT(r.similarity->score.similarity, r.similarity->grid.back().similarity - 0.02);
  SM_ASSERT_OK_AND_ASSIGN(const std::string text, ReadFileToString(o.output.dir + "/report.json"));
  const nlohmann::json report = nlohmann::json::parse(text);
  ASSERT_TRUE(report["similarity"].contains("floor_warning")) << report["similarity"].dump();
  EXPECT_THAT(report["similarity"]["floor_warning"]["text"].get<std::string>(),
              ::testing::HasSubstr("is under the grid model's"));
}

}  // namespace
}  // namespace sheetmesh
