#include "worker/pipeline/run/pipeline_config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/testing/status_matchers.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::IsOk;
using ::sheetmesh::testing::StatusIs;
using ::testing::HasSubstr;

TEST(PipelineConfigTest, EveryGroupSetsItsParameters) {
  PipelineOptions o;
  ASSERT_THAT(ApplyPipelineConfig(R"({
      "input": {"labels": [2, 3], "dims": [10, 20, 30], "dtype": "uint16", "spacing": [1, 1, 2]},
      "extract": true,
      "refine": {"enabled": false, "close_radius": 2},
      "detect": {"t": 2.5, "R": 9, "rounds": 2},
      "M": 1234,
      "separate": {"r": 6, "D_ang": 140},
      "remove_minor": {"enabled": false},
      "recover": {"rounds": 3},
      "surface": {"r": 9, "seed": 5, "method": "paper", "lloyd_tol": 0.01},
      "radius_search": {"goal": "target", "target_similarity": 0.6},
      "similarity": {"model": "vertex", "grid_rates": [2]},
      "volume_mesh": {"improve_passes": 2, "improve_target_degrees": 45,
                      "improve_insert_below_degrees": 12, "improve_floor_degrees": 25,
                      "improve_split_sheets_below_degrees": 9, "improve_radius_weight": 0.25,
                      "snap_clear_voxels": 2.5, "wedge_degrees": 15, "wedge_voxels": 0.5,
                      "overlap_voxels": 0.8, "overlap_degrees": 20, "lattice": 0.85},
      "output": {"formats": ["ply"], "model": false}})",
                                  "c.json", &o),
              IsOk());
  EXPECT_EQ(o.input.selection.ToString(), "labels=2,3");
  EXPECT_EQ(*o.input.open.raw_dims, (Dims{10, 20, 30}));
  EXPECT_EQ(*o.input.open.raw_dtype, DType::kUInt16);
  EXPECT_EQ(o.input.open.spacing->z, 2);
  EXPECT_TRUE(o.extract);
  EXPECT_FALSE(o.extraction.refine);
  EXPECT_EQ(o.extraction.refine_close_radius, 2);
  EXPECT_EQ(o.extraction.detect_extend.half_thickness_voxels, 2.5);
  EXPECT_EQ(o.extraction.detect_extend.max_rounds, 2);
  EXPECT_EQ(o.extraction.min_object_voxels, 1234u);
  EXPECT_EQ(o.extraction.separation.dihedral_degrees, 140);
  EXPECT_FALSE(o.extraction.remove_minor);
  EXPECT_EQ(o.extraction.recover_extend.max_rounds, 3);
  EXPECT_EQ(o.surface.scvd.radius_voxels, 9);
  EXPECT_EQ(o.surface.scvd.seed, 5u);
  EXPECT_FALSE(o.surface.triangles.rim) << "method paper";
  EXPECT_TRUE(o.search_radius);
  EXPECT_EQ(o.radius_search.goal, RadiusGoal::kTargetSimilarity);
  EXPECT_EQ(o.score.height, PrismHeight::kVertex);
  EXPECT_TRUE(o.output.ply);
  EXPECT_FALSE(o.output.vtp);
  EXPECT_FALSE(o.output.model);
  EXPECT_EQ(o.volume.improve.passes, 2);
  EXPECT_EQ(o.volume.improve.target_degrees, 45);
  EXPECT_EQ(o.volume.improve.insert_below_degrees, 12);
  EXPECT_EQ(o.volume.improve.smoothing_floor_degrees, 25);
  EXPECT_EQ(o.volume.improve.split_sheets_below_degrees, 9);
  EXPECT_EQ(o.volume.improve.radius_weight, 0.25);
  EXPECT_EQ(o.volume.plc.snap_clear_voxels, 2.5);
  EXPECT_EQ(o.volume.plc.wedge_degrees, 15);
  EXPECT_EQ(o.volume.plc.wedge_voxels, 0.5);
  EXPECT_EQ(o.volume.plc.overlap_voxels, 0.8);
  EXPECT_EQ(o.volume.plc.overlap_degrees, 20);
  EXPECT_EQ(o.volume.plc.lattice, 0.85);
}

TEST(PipelineConfigTest, MistakesNameTheFileTheKeyAndTheValue) {
  struct Case {
    const char* json;
    const char* message;
  };
  const Case cases[] = {
      {R"({"surface": {"radius": 7}})", "unknown key 'surface.radius'"},
      {R"({"separate": {"D_ang": "wide"}})", "'separate.D_ang' = \"wide\" must be a number"},
      {R"({"separate": {"D_ang": 200}})", "D_ang = 200"},
      {R"({"surface": {"r": -1}})", "r = -1"},
      {R"({"surface": {"method": "fast"}})", "'surface.method' = \"fast\""},
      {R"({"input": {"window": [5, 1]}})", "'input.window'"},
      {R"({"M": -3})", "'M' = -3"},
      {R"({"extract": true, "detect": {"R": 0}})", "detect.R = 0"},
      {R"({"volume_mesh": {"improve_passes": -1}})", "volume_mesh.improve_passes = -1"},
      {R"({"volume_mesh": {"improve_target_degrees": 80}})", "improve_target_degrees = 80"},
      {R"({"volume_mesh": {"improve_insert_below_degrees": 60}})",
       "improve_insert_below_degrees = 60"},
      {R"({"volume_mesh": {"improve_floor_degrees": -2}})", "improve_floor_degrees = -2"},
      {R"({"volume_mesh": {"improve_split_sheets_below_degrees": 75}})",
       "volume_mesh.improve_split_sheets_below_degrees = 75"},
      {R"({"volume_mesh": {"snap_clear_voxels": -1}})", "volume_mesh.snap_clear_voxels = -1"},
      {R"({"volume_mesh": {"improve_radius_weight": 1.5}})",
       "volume_mesh.improve_radius_weight = 1.5"},
      {R"({"volume_mesh": {"overlap_voxels": -1}})", "volume_mesh.overlap_voxels = -1"},
      {R"({"volume_mesh": {"wedge_degrees": 40}})", "volume_mesh.wedge_degrees = 40"},
      {R"({"volume_mesh": {"wedge_voxels": -0.5}})", "volume_mesh.wedge_voxels = -0.5"},
      {R"({"volume_mesh": {"overlap_degrees": 90}})", "volume_mesh.overlap_degrees = 90"},
      {R"({"volume_mesh": {"lattice": 0.1}})", "volume_mesh.lattice = 0.1 must be 0 or in"},
      {R"({"surface": )", "not valid JSON"},
      {R"([1, 2])", "must be an object"},
  };
  for (const Case& c : cases) {
    PipelineOptions o;
    EXPECT_THAT(ApplyPipelineConfig(c.json, "cfg.json", &o),
                StatusIs(absl::StatusCode::kInvalidArgument,
                         ::testing::AllOf(HasSubstr("cfg.json"), HasSubstr(c.message))))
        << c.json;
  }
}

}  // namespace
}  // namespace sheetmesh
