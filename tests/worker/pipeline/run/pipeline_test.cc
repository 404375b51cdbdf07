#include "worker/pipeline/run/pipeline.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "common/file_util.h"
#include "tests/testing/grey_phantoms.h"
#include "tests/testing/preset_sheets.h"
#include "tests/testing/shared_data.h"
#include "tests/testing/status_matchers.h"
#include "tests/testing/temp_dir.h"
#include "worker/pipeline/mesh/mesh_io.h"
#include "worker/pipeline/phantom/phantom.h"
#include "worker/pipeline/phantom/phantom_presets.h"
#include "worker/pipeline/volume/raw_io.h"
#include "worker/pipeline/volume/volume_open.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::PresetRawFile;
using ::sheetmesh::testing::StatusIs;
using ::sheetmesh::testing::TempDir;

std::string SmallPhantom(const TempDir& tmp) {
  PhantomOptions o;
  o.dims = {64, 56, 48};
  o.num_sheets = 2;
  o.num_specks = 5;
  o.aperture_voxels = 4;
  PhantomTruth truth = *PlanPhantom(o);
  const std::string path = tmp.File("p_64x56x48_u8.raw");
  VolumeInfo info;
  info.dims = o.dims;
  auto sink = *CreateRawWriter(path, info);
  EXPECT_TRUE(GeneratePhantom(&truth, *sink).ok());
  return path;
}

// A run of the small phantom at r with the volume mesh, written to tmp/out.
PipelineOptions VolumeRun(const TempDir& tmp, double r) {
  PipelineOptions o;
  o.input.path = SmallPhantom(tmp);
  o.output.dir = tmp.File("out");
  o.surface.scvd.radius_voxels = r;
  o.volume_mesh = true;
  return o;
}

class Stages : public ProgressObserver {
 public:
  bool OnProgress(absl::string_view stage, double, absl::string_view) override {
    if (seen.empty() || seen.back() != stage) seen.emplace_back(stage);
    return !(cancel_at == stage);
  }
  std::vector<std::string> seen;
  std::string cancel_at;
};

TEST(PipelineTest, RunWritesMeshesAndAReport) {
  TempDir tmp;
  PipelineOptions o;
  o.input.path = SmallPhantom(tmp);
  o.output.dir = tmp.File("out");
  o.surface.scvd.radius_voxels = 6;
  Stages stages;
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport r, RunPipeline(o, Progress(&stages, "")));
  EXPECT_EQ(stages.seen, PlannedStages(o));
  EXPECT_GT(r.surface->triangles, 50u);
  EXPECT_GT(r.similarity->score.similarity, 0.5);
  // Measured (not the -1 of "not asked"), and within the sheets' reach at r = 6.
  EXPECT_GT(r.similarity->score.hausdorff, 0);
  EXPECT_LT(r.similarity->score.hausdorff, 2 * o.surface.scvd.radius_voxels);
  ASSERT_EQ(r.similarity->grid.size(), 3u);
  for (const char* f : {"surface.ply", "surface.vtp", "surface.obj", "report.json"}) {
    EXPECT_TRUE(std::filesystem::exists(tmp.File(std::string("out/") + f))) << f;
  }
  SM_ASSERT_OK_AND_ASSIGN(std::string text, ReadFileToString(tmp.File("out/report.json")));
  const nlohmann::json j = nlohmann::json::parse(text);
  EXPECT_EQ(j["surface"]["triangles"].get<uint64_t>(), r.surface->triangles);
  EXPECT_DOUBLE_EQ(j["similarity"]["similarity"].get<double>(), r.similarity->score.similarity);
  EXPECT_EQ(j["parameters"]["r"].get<double>(), 6);
  EXPECT_TRUE(j["seconds"].contains("surface"));
  SM_ASSERT_OK_AND_ASSIGN(TriangleMesh back, ReadMesh(tmp.File("out/surface.ply")));
  EXPECT_EQ(back.faces.size(), r.surface->triangles);
}

// surface.bricks: the SCVD and its triangles built brick by brick, then every later stage
// (fits, similarity, the volume mesh) on the joined surface; against one brick holding the
// whole sheet (the halos here cover the small volume, so both passes are exact).
TEST(PipelineTest, SurfaceInBricksMeshesLikeTheWholeSheetAndFeedsTheVolumeMesh) {
  TempDir tmp;
  PipelineOptions whole = VolumeRun(tmp, 5);
  whole.surface.scvd.lloyd_max_iter = 8;
  whole.surface.bricks.brick = 64;  // one brick
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport w, RunPipeline(whole));
  EXPECT_EQ(w.surface->bricks, 1u);
  PipelineOptions bricked = whole;
  bricked.output.dir = tmp.File("bricked");
  bricked.surface.bricks.brick = 32;  // the smallest brick: its halo (given) and 4 r + t_max
  bricked.surface.bricks.halo = 32;
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport b, RunPipeline(bricked));
  EXPECT_GE(b.surface->bricks, 8u);
  EXPECT_EQ(b.surface->seam_mismatches, 0u);
  EXPECT_GT(b.surface->brick_halo, 0);
  EXPECT_EQ(b.surface->triangles, w.surface->triangles);
  // The joined mesh lists its vertices brick by brick: the fits' sums run in another order.
  EXPECT_NEAR(b.similarity->score.similarity, w.similarity->score.similarity, 1e-3);
  EXPECT_EQ(b.surface->topology.boundary_loops, w.surface->topology.boundary_loops);
  ASSERT_TRUE(b.volume_mesh.has_value());
  EXPECT_GT(b.volume_mesh->tetrahedra, 100u);
  SM_ASSERT_OK_AND_ASSIGN(std::string text, ReadFileToString(tmp.File("bricked/report.json")));
  const nlohmann::json j = nlohmann::json::parse(text);
  EXPECT_EQ(j["surface"]["bricks"]["bricks"].get<uint64_t>(), b.surface->bricks);
  EXPECT_EQ(j["parameters"]["surface"]["bricks"].get<int64_t>(), 32);

  // Below the sheet's floor (hardening, third round: 1 voxel never ended): refused, naming
  // the smallest brick.
  PipelineOptions tiny = bricked;
  tiny.output.dir = tmp.File("tiny");
  tiny.surface.bricks.halo = 0;
  EXPECT_THAT(RunPipeline(tiny),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       ::testing::AllOf(::testing::HasSubstr("surface.bricks = 32"),
                                        ::testing::HasSubstr("give at least"))));

  // An error-driven density has the whole sheet's scale: refused, named.
  bricked.surface.error_density = 1;
  bricked.output.dir = tmp.File("refused");
  EXPECT_THAT(RunPipeline(bricked),
              StatusIs(absl::StatusCode::kInvalidArgument, ::testing::HasSubstr("surface.bricks")));
}

TEST(PipelineTest, AVolumePathThatIsNotUtf8GivesAReportWithTheNameEscaped) {
  // The same writer makes a job's report in a worker thread of the server: it must never
  // throw (nlohmann::json does on bytes that are not UTF-8, and that ended the process).
  TempDir tmp;
  const std::string plain = SmallPhantom(tmp);
  const std::string odd = tmp.File("p_\xff\xfe_64x56x48_u8.raw");
  std::filesystem::copy_file(plain, odd);
  PipelineOptions o;
  o.input.path = odd;
  o.output.dir = tmp.File("out");
  o.surface.scvd.radius_voxels = 9;
  o.score.hausdorff = false;
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport r, RunPipeline(o));
  SM_ASSERT_OK_AND_ASSIGN(std::string text, ReadFileToString(tmp.File("out/report.json")));
  const nlohmann::json j = nlohmann::json::parse(text);
  EXPECT_NE(j["input"]["path"].get<std::string>().find("\xef\xbf\xbd"), std::string::npos)
      << "the bad bytes are written as U+FFFD";
}

TEST(PipelineTest, RunWithExtractionWritesTheLabelledModelAndPieces) {
  TempDir tmp;
  PipelineOptions o;
  o.input.path = SmallPhantom(tmp);
  o.output.dir = tmp.File("out");
  o.extract = true;
  o.score.hausdorff = false;
  Stages stages;
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport r, RunPipeline(o, Progress(&stages, "")));
  EXPECT_EQ(stages.seen, PlannedStages(o));
  EXPECT_GE(r.extraction->pieces, 2u);
  EXPECT_EQ(r.geology.size(), r.extraction->pieces);
  EXPECT_GT(r.similarity->raw->similarity, 0.4);
  for (const char* f : {"model.vdb", "pieces.csv"}) {
    EXPECT_TRUE(std::filesystem::exists(tmp.File(std::string("out/") + f))) << f;
  }
  // Nothing the size of the box unless asked: the report says what was left out.
  EXPECT_FALSE(std::filesystem::exists(tmp.File("out/model_labels_64x56x48.h5")));
  EXPECT_FALSE(std::filesystem::exists(tmp.File("out/model_labels_64x56x48_u16.raw")));
  const nlohmann::json j = nlohmann::json::parse(*ReadFileToString(tmp.File("out/report.json")));
  EXPECT_EQ(j["not_written"][0]["file"], "model_labels");
  EXPECT_THAT(j["not_written"][0]["why"].get<std::string>(),
              ::testing::HasSubstr("output.label_volume"));
  // Asked for: chunked HDF5 whose labels are model.vdb's; raw, 2 bytes a voxel.
  PipelineOptions h5 = o;
  h5.output.dir = tmp.File("h5");
  h5.output.label_volume = DenseLabels::kHdf5;
  h5.output.dropped = true;
  ASSERT_THAT(RunPipeline(h5, {}).status(), testing::IsOk());
  SM_ASSERT_OK_AND_ASSIGN(auto labels, OpenVolume(tmp.File("h5/model_labels_64x56x48.h5")));
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume dense, ReadDense(*labels));
  uint64_t labelled = 0;
  const Dims& d = dense.info.dims;
  for (int64_t z = 0; z < d.nz; ++z)
    for (int64_t y = 0; y < d.ny; ++y)
      for (int64_t x = 0; x < d.nx; ++x) labelled += dense.At(x, y, z) > 0;
  EXPECT_EQ(labelled, r.extraction->model_voxels);
  EXPECT_TRUE(std::filesystem::exists(tmp.File("h5/dropped_labels_64x56x48.h5")));
  PipelineOptions raw = o;
  raw.output.dir = tmp.File("raw");
  raw.output.label_volume = DenseLabels::kRaw;
  ASSERT_THAT(RunPipeline(raw, {}).status(), testing::IsOk());
  EXPECT_EQ(std::filesystem::file_size(tmp.File("raw/model_labels_64x56x48_u16.raw")),
            64u * 56 * 48 * 2);
  EXPECT_EQ(j["extraction"]["steps"].size(), 5u);
  EXPECT_EQ(j["pieces"].size(), r.extraction->pieces);
  EXPECT_EQ(j["similarity"]["against"], "extracted model");
}

TEST(PipelineTest, VolumeStageWritesTheFemFormats) {
  TempDir tmp;
  PipelineOptions o;
  o.input.path = SmallPhantom(tmp);
  o.output.dir = tmp.File("out");
  o.extract = true;
  o.output.split = true;  // turns the volume mesh on
  o.score.hausdorff = false;
  Stages stages;
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport r, RunPipeline(o, Progress(&stages, "")));
  EXPECT_EQ(stages.seen, PlannedStages(o));
  ASSERT_TRUE(r.volume_mesh.has_value());
  EXPECT_GT(r.volume_mesh->tetrahedra, 100u);
  EXPECT_EQ(r.volume_mesh->conformity.conforming, r.volume_mesh->conformity.sheet_triangles);
  EXPECT_NEAR(r.volume_mesh->quality.volume, 64.0 * 56 * 48, 1e-6 * 64 * 56 * 48);
  for (const char* f : {"volume.vtu", "volume.msh", "volume.inp", "volume.exo", "volume_split.inp",
                        "volume_split_ccx.inp", "volume_split.exo"}) {
    EXPECT_TRUE(std::filesystem::exists(tmp.File(std::string("out/") + f))) << f;
  }
  const nlohmann::json j = nlohmann::json::parse(*ReadFileToString(tmp.File("out/report.json")));
  EXPECT_EQ(j["volume_mesh"]["tetrahedra"].get<uint64_t>(), r.volume_mesh->tetrahedra);
  EXPECT_TRUE(j["volume_mesh"]["quality"].contains("radius_aspect"));
  // The split: one interface per sheet face, a copy for every sheet node not on a rim.
  ASSERT_TRUE(r.volume_split.has_value());
  EXPECT_EQ(r.volume_split->interfaces + r.volume_split->unsplit_faces, r.volume_mesh->sheet_faces);
  EXPECT_GT(r.volume_split->added_nodes, 0u);
  EXPECT_GE(r.volume_split->added_nodes, r.volume_split->sheet_nodes - r.volume_split->rim_nodes);
  EXPECT_EQ(j["volume_split"]["interfaces"].get<uint64_t>(), r.volume_split->interfaces);
}

// The flow stage on the phantom's volume mesh (which flow turns on): a tensor in the report,
// every stage seen; a volume of unknown unit is refused before any work.
TEST(PipelineTest, FlowGivesThePermeabilityTensorOfTheVolumeMesh) {
  TempDir tmp;
  PipelineOptions o;
  o.input.path = SmallPhantom(tmp);
  o.output.dir = tmp.File("out");
  o.flow.enabled = true;
  o.score.hausdorff = false;
  o.input.open.unit = "um";
  Stages stages;
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport r, RunPipeline(o, Progress(&stages, "")));
  EXPECT_EQ(stages.seen, PlannedStages(o));
  ASSERT_TRUE(r.flow.has_value());
  for (int i = 0; i < 3; ++i) {
    // The sheets raise every diagonal term above the rock's.
    EXPECT_GT(r.flow->tensor[i][i], o.flow.matrix_permeability);
    EXPECT_GE(r.flow->principal[i], 0.99 * o.flow.matrix_permeability);
  }
  EXPECT_GT(r.flow->sheet_faces, 0u);
  const nlohmann::json j = nlohmann::json::parse(*ReadFileToString(tmp.File("out/report.json")));
  EXPECT_EQ(j["flow"]["permeability_m2"].size(), 3u);
  EXPECT_NEAR(j["flow"]["permeability_darcy"][0][0].get<double>(),
              r.flow->tensor[0][0] / kSquareMetresPerDarcy,
              1e-9 * r.flow->tensor[0][0] / kSquareMetresPerDarcy);

  PipelineOptions unitless = o;
  unitless.input.open.unit.clear();
  EXPECT_THAT(RunPipeline(unitless, {}),
              StatusIs(absl::StatusCode::kInvalidArgument, ::testing::HasSubstr("input.unit")));
  EXPECT_TRUE(r.volume_mesh.has_value());
  // The pressures and velocities of the three solves in volume.vtu.
  const std::string vtu = *ReadFileToString(tmp.File("out/volume.vtu"));
  for (const char* name : {"pressure_x", "pressure_z", "velocity_x", "velocity_y"}) {
    EXPECT_THAT(vtu, ::testing::HasSubstr(absl::StrCat("Name=\"", name, "\""))) << name;
  }
  EXPECT_THAT(vtu, ::testing::HasSubstr("<PointData"));
  // The tensor's chart among the previews: its bars are the report's numbers in darcy.
  EXPECT_TRUE(std::filesystem::exists(tmp.File("out/preview_permeability.png")));
  const nlohmann::json chart = j["previews"].back();
  EXPECT_EQ(chart["kind"], "permeability");
  ASSERT_EQ(chart["groups"].size(), 6u);
  for (int d = 0; d < 3; ++d) {
    EXPECT_NEAR(chart["groups"][d]["values"][0].get<double>(),
                j["flow"]["permeability_darcy"][d][d].get<double>(),
                1e-9 * chart["groups"][d]["values"][0].get<double>());
  }
  EXPECT_EQ(chart["groups"][0]["values"].size(), 3u);  // tensor, permeameter, the image's

  // Without the image's reference: none, and the report says why.
  PipelineOptions without = o;
  without.flow.image_reference = false;
  without.output.dir = tmp.File("without");
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport w, RunPipeline(without, {}));
  EXPECT_FALSE(w.flow_image.has_value());
  EXPECT_THAT(w.flow_image_skipped, ::testing::HasSubstr("permeability.image_reference"));
  EXPECT_EQ(w.flow->tensor, r.flow->tensor);
}

// A planar slab of constant aperture through the box: the mesh's permeameters along it and
// the image's own (the cubic law on its voxels) agree within 5%.
TEST(PipelineTest, AFlatSlabsPermeabilityMatchesTheImagesWithinFivePercent) {
  TempDir tmp;
  std::string bytes(40 * 40 * 40, '\0');
  for (int z = 18; z < 22; ++z) std::fill_n(bytes.begin() + z * 1600, 1600, '\xff');
  ASSERT_TRUE(WriteFileAtomically(tmp.File("slab_40x40x40_u8.raw"), bytes).ok());
  PipelineOptions o;
  o.input.path = tmp.File("slab_40x40x40_u8.raw");
  o.input.selection = PhaseSelection::Labels({255});
  o.input.open.unit = "um";
  o.input.open.spacing = Vec3(5, 5, 5);
  o.surface.scvd.radius_voxels = 5;
  o.flow.enabled = true;
  o.score.hausdorff = false;
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport r, RunPipeline(o, {}));
  ASSERT_TRUE(r.flow_image.has_value());
  for (int d = 0; d < 2; ++d) EXPECT_NEAR(r.flow_image->mesh_to_image[d], 1, 0.05) << d;
}

TEST(PipelineTest, CancelledRunLeavesNoFiles) {
  TempDir tmp;
  PipelineOptions o;
  o.input.path = SmallPhantom(tmp);
  o.output.dir = tmp.File("out");
  Stages stages;
  stages.cancel_at = "similarity";
  EXPECT_THAT(RunPipeline(o, Progress(&stages, "")), StatusIs(absl::StatusCode::kCancelled));
  EXPECT_FALSE(std::filesystem::exists(tmp.File("out/report.json")));
  EXPECT_FALSE(std::filesystem::exists(tmp.File("out/surface.ply")));
}

TEST(PipelineTest, EmptySelectionFailsNamingTheFile) {
  TempDir tmp;
  PipelineOptions o;
  o.input.path = SmallPhantom(tmp);
  o.input.selection = PhaseSelection::Labels({7});
  EXPECT_THAT(RunPipeline(o), StatusIs(absl::StatusCode::kInvalidArgument,
                                       ::testing::HasSubstr("p_64x56x48_u8.raw")));
}

// A grey scan of one sheet half a voxel open, blurred and noisy, as float32: --grey finds
// it, meshes it, and its aperture comes from the grey levels, with the voxel count beside.
std::string GreyScan(const TempDir& tmp, const std::vector<float>& values, const Dims& d) {
  const std::string path = tmp.File(absl::StrCat("scan_", d.ToString(), "_f32.raw"));
  std::string bytes(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(float));
  EXPECT_TRUE(WriteFileAtomically(path, bytes).ok());
  return path;
}

TEST(PipelineTest, AGreyScanGivesTheSheetAndItsApertureFromTheGreyLevels) {
  TempDir tmp;
  testing::GreyPhantomOptions g;
  g.dims = {56, 48, 48};
  testing::GreySheet sheet;
  sheet.center = {33, 24, 24};
  sheet.normal = Normalized(Vec3(0.2, 0.3, 1));
  sheet.along = Normalized(Cross(sheet.normal, Vec3(0, 1, 0)));
  sheet.aperture = 0.5;
  g.sheets = {sheet};
  PipelineOptions o;
  o.input.path = GreyScan(tmp, testing::MakeGreyPhantom(g).values, g.dims);
  o.grey.enabled = true;
  o.surface.scvd.radius_voxels = 5;
  o.output.dir = tmp.File("out");
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport r, RunPipeline(o));
  ASSERT_TRUE(r.grey_apertures.has_value());
  EXPECT_TRUE(r.grey_apertures->measured) << r.grey_apertures->levels.problem;
  EXPECT_NEAR(r.grey_apertures->mean_voxels, 0.5, 0.1);
  EXPECT_GT(r.grey_apertures->counted_mean_voxels, 1.0);  // a detected band is voxels wide
  EXPECT_GT(r.similarity->score.similarity, 0.6);
  // The piece's aperture (pieces.csv, the report's pieces) is the grey levels' too.
  ASSERT_EQ(r.geology.size(), 1u);
  EXPECT_NEAR(r.geology[0].mean_aperture, r.grey_apertures->mean_voxels, 0.05);
  const nlohmann::json j = nlohmann::json::parse(r.ToJson());
  EXPECT_TRUE(j["grey"]["levels"]["void_measured"].get<bool>());
  EXPECT_EQ(j["grey"]["sheetness"]["noise_per_scale"].size(), 3u);
  // The writers carry it: the surface's aperture is the grey levels'.
  SM_ASSERT_OK_AND_ASSIGN(std::string vtp, ReadFileToString(tmp.File("out/surface.vtp")));
  EXPECT_THAT(vtp, ::testing::HasSubstr("Name=\"aperture\""));
}

TEST(PipelineTest, AGreyRunOnAVolumeWithoutGreyLevelsFailsNamingIt) {
  TempDir tmp;
  const Dims d{16, 16, 16};
  std::vector<float> labels(d.num_voxels());
  for (size_t i = 0; i < labels.size(); ++i) labels[i] = float(i % 4 == 0);
  PipelineOptions o;
  o.input.path = GreyScan(tmp, labels, d);
  o.grey.enabled = true;
  EXPECT_THAT(RunPipeline(o),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       ::testing::AllOf(::testing::HasSubstr("scan_16x16x16_f32.raw"),
                                        ::testing::HasSubstr("input.labels"))));
  std::vector<float> flat(d.num_voxels(), 3.5f);
  o.input.path = GreyScan(tmp, flat, d);
  EXPECT_THAT(RunPipeline(o),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       ::testing::HasSubstr("needs contrast, and every voxel is 3.5")));
}

TEST(PipelineTest, AnRThatGivesNoTriangleFailsNamingR) {
  // Once a success with 0 triangles, similarity 0 and a volume mesh of the box alone.
  TempDir tmp;
  const PipelineOptions o = VolumeRun(tmp, 40);
  EXPECT_THAT(RunPipeline(o), StatusIs(absl::StatusCode::kInvalidArgument,
                                       ::testing::AllOf(::testing::HasSubstr("r = 40 voxels"),
                                                        ::testing::HasSubstr("no triangle"),
                                                        ::testing::HasSubstr("lower r"))));
  EXPECT_FALSE(std::filesystem::exists(tmp.File("out/volume.vtu")));
}

TEST(PipelineTest, AFailedVolumeStageKeepsTheSurfaceAndSaysSo) {
  // Once the folder was not even made: the surface, its score and previews were lost.
  TempDir tmp;
  PipelineOptions o = VolumeRun(tmp, 6);
  o.volume.max_tetrahedra = 10;  // below what any volume mesh of these sheets needs
  EXPECT_THAT(RunPipeline(o),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       ::testing::AllOf(::testing::HasSubstr("max_tetrahedra = 10"),
                                        ::testing::HasSubstr("the volume stage failed; kept in"),
                                        ::testing::HasSubstr("surface.ply"))));
  for (const char* f : {"surface.ply", "report.json"}) {
    EXPECT_TRUE(std::filesystem::exists(tmp.File(std::string("out/") + f))) << f;
  }
  EXPECT_FALSE(std::filesystem::exists(tmp.File("out/volume.vtu")));
  SM_ASSERT_OK_AND_ASSIGN(std::string text, ReadFileToString(tmp.File("out/report.json")));
  const nlohmann::json j = nlohmann::json::parse(text);
  EXPECT_EQ(j["failed"]["stage"], "volume");
  EXPECT_THAT(j["failed"]["error"].get<std::string>(), ::testing::HasSubstr("max_tetrahedra"));
  EXPECT_GT(j["similarity"]["similarity"].get<double>(), 0.5);
  EXPECT_FALSE(j.contains("volume_mesh"));
}

TEST(PipelineTest, TheReportScoresTheSheetsTheVolumeMeshHas) {
  // The volume mesh snaps rims onto the box and mends clashes: its sheets are not exactly
  // the surface scored. The report scores them too, with physical spacing undone.
  TempDir tmp;
  PipelineOptions o = VolumeRun(tmp, 6);
  o.input.open.spacing = Vec3{0.005, 0.005, 0.005};
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport r, RunPipeline(o));
  ASSERT_TRUE(r.volume_mesh && r.volume_mesh->delivered_similarity);
  // Two sheet vertices move a voxel for the angles on this small phantom, which its few
  // large triangles feel: 0.607 against the surface's 0.638 (a box triangle split elsewhere
  // in the mesh changes which two and how; within 0.03 without it).
  EXPECT_NEAR(*r.volume_mesh->delivered_similarity, r.similarity->score.similarity, 0.04);
  EXPECT_GT(*r.volume_mesh->delivered_similarity, 0.5);
  const nlohmann::json j = nlohmann::json::parse(r.ToJson());
  EXPECT_DOUBLE_EQ(j["volume_mesh"]["similarity_of_its_sheets"].get<double>(),
                   *r.volume_mesh->delivered_similarity);
}

TEST(PipelineTest, ABodyTheBoxCutsIsScoredClosedByItsFacesOnTheBox) {
  // The thick_slab preset (100 x 100 x 111, one slab 30-50 voxels thick across the box),
  // meshed as a body: its walls in the volume mesh are open where the box cuts it, and the
  // score of the volume mesh's sheets filled the wrong side (-0.0065 against 0.95 at r = 5).
  TempDir tmp;
  const std::string path = PresetRawFile(tmp, "thick_slab");
  PipelineOptions o;
  o.input.path = path;
  o.output.dir = tmp.File("out");
  o.extract = false;
  o.surface.scvd.radius_voxels = 7;
  o.volume_mesh = true;
  o.score.hausdorff = false;
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport r, RunPipeline(o));
  ASSERT_TRUE(r.volume_mesh && r.volume_mesh->delivered_similarity);
  ASSERT_FALSE(r.volume_mesh->bodies.empty()) << "the slab is meshed as a body";
  EXPECT_GT(r.similarity->score.similarity, 0.8);
  EXPECT_NEAR(*r.volume_mesh->delivered_similarity, r.similarity->score.similarity, 0.05);
}

TEST(PipelineTest, SheetFacesCarryAnApertureThatIsZeroOnlyOverAHole) {
  // The fitted heights leave faces at 0 where neighbours cover them; the aperture beside
  // them (surface.ply's aperture_voxels) is 0 only over a hole, and the report counts both.
  TempDir tmp;
  PipelineOptions o = VolumeRun(tmp, 3);
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport r, RunPipeline(o));
  SM_ASSERT_OK_AND_ASSIGN(TriangleMesh surface, ReadMesh(tmp.File("out/surface.ply")));
  ASSERT_EQ(surface.face_aperture_voxels.size(), surface.faces.size());
  size_t zero_thickness = 0, zero_aperture = 0;
  for (size_t f = 0; f < surface.faces.size(); ++f) {
    if (surface.IsBodyFace(f)) continue;
    zero_thickness += surface.face_thickness_voxels[f] == 0;
    zero_aperture += surface.face_aperture_voxels[f] == 0;
  }
  const nlohmann::json j = nlohmann::json::parse(r.ToJson())["surface"]["apertures"];
  EXPECT_GT(zero_thickness, 0u) << "r = 3 leaves covered faces at 0 on this phantom";
  EXPECT_EQ(zero_aperture, j["hole_faces"].get<size_t>());
  // Covered faces, and junction faces fitted at 0, were given their sheet's aperture.
  EXPECT_GE(zero_thickness - zero_aperture, j["covered_faces_given_their_sheets"].get<size_t>());
  EXPECT_GT(j["covered_faces_given_their_sheets"].get<size_t>(), 0u);
  EXPECT_GT(j["junction_faces"].get<size_t>(), 0u);
}

// The NETL fracture (../shared/data) at radius r, its sheet label, no Hausdorff distance.
PipelineOptions Netl(double r) {
  PipelineOptions o;
  o.input.path = testing::SharedDataFile("netl_binary_fracture_small.tif");
  o.input.selection = PhaseSelection::Labels({255});
  o.surface.scvd.radius_voxels = r;
  o.score.hausdorff = false;
  return o;
}

TEST(PipelineTest, NetlFractureMeshesWithItsKnownShape) {
  SM_REQUIRE_SHARED_DATA("netl_binary_fracture_small.tif");
  PipelineOptions o = Netl(7);
  o.extract = false;  // the image's own components, every one
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport r, RunPipeline(o));
  EXPECT_EQ(r.sheet_voxels, 84595u);
  EXPECT_EQ(r.components, 63u);
  // One sheet: the 62 small pieces are too small for a triangle at r = 7.
  EXPECT_EQ(r.surface->skipped_components, 62u);
  EXPECT_GT(r.similarity->score.similarity, 0.7);
  EXPECT_EQ(r.surface->topology.duplicate_faces, 0u);
  EXPECT_EQ(r.surface->topology.inconsistent_edges, 0u);
}

TEST(PipelineTest, NetlFractureVolumeMeshConformsWithoutFlatTetrahedra) {
  // The NETL sheet at r = 7 once gave TetGen output whose .face file listed sheet faces no
  // tetrahedron had (TetGen's own vertex insertion), and rim triangles lying on the sheet
  // filled the mesh with slivers below 0.01 degrees.
  SM_REQUIRE_SHARED_DATA("netl_binary_fracture_small.tif");
  TempDir tmp;
  PipelineOptions o = Netl(7);
  o.output.dir = tmp.File("out");
  o.volume_mesh = true;
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport r, RunPipeline(o));
  EXPECT_GT(r.volume_mesh->conformity.sheet_triangles, 400u);
  EXPECT_EQ(r.volume_mesh->conformity.conforming, r.volume_mesh->conformity.sheet_triangles);
  EXPECT_EQ(r.volume_mesh->conformity.orphan_faces, 0u);
  EXPECT_NEAR(r.volume_mesh->quality.volume, 200.0 * 42 * 100, 1e-9 * 200 * 42 * 100);
  EXPECT_EQ(r.volume_mesh->quality.inverted, 0u);
  EXPECT_GT(r.volume_mesh->dropped_overlaps, 0u);
  EXPECT_GT(r.volume_mesh->quality.min_dihedral.min, 1.0);
  EXPECT_GT(r.volume_mesh->quality.min_dihedral.mean, 45.0);
  // By default TetGen adds no point on a facet: each sheet triangle is one tetrahedron
  // face, but for the few the improvement splits by a vertex on a sheet face (into 3) or
  // sheet edge (each face on it into 2); the box faces and the space off the sheets are
  // seeded.
  const TetImproveReport& im = r.volume_mesh->improvement;
  EXPECT_GE(r.volume_mesh->sheet_faces, r.volume_mesh->conformity.sheet_triangles);
  EXPECT_LE(r.volume_mesh->sheet_faces - r.volume_mesh->conformity.sheet_triangles,
            2 * im.sheet_face_splits + 4 * im.sheet_edge_splits);
  EXPECT_LT(im.sheet_face_splits + im.sheet_edge_splits, 20u);
  EXPECT_GT(r.volume_mesh->box_points, 0u);
  EXPECT_GT(r.volume_mesh->seed_points, 0u);
}

// At r = 11 the NETL sheet's own vertices pinned a sliver of 1.09 degrees: a flat gap
// framed by sheet edges, four sheet vertices nearly on one circle, out of reach of every
// vertex off the sheet. Sheet vertices off the box and off junctions may now move up to
// improve.sheet_move_voxels (1) for the worst tetrahedra of their star: every angle is at
// least 10 degrees, a handful of vertices moved, none farther than the reach, and the
// volume mesh's sheets score within 0.02 of the unmoved ones.
// NETL at r = 11 once kept a sliver the improvement mended only by moving sheet vertices; the
// PLC's contact mends now close that gap before TetGen (a rim on the box beside a triangle of
// its sheet: 13.12 degrees with the vertices held, 10.85 with no contact mend at all). With
// the mends off, the moves that remain are few, within a voxel, and cost the sheets little.
TEST(PipelineTest, NetlAtRadius11MeshesAtTenDegreesWithFewBoundedSheetMoves) {
  SM_REQUIRE_SHARED_DATA("netl_binary_fracture_small.tif");
  TempDir tmp;
  PipelineOptions o = Netl(11);
  o.extract = false;
  o.score.grid_rates.clear();
  o.volume_mesh = true;
  o.volume.plc.contact_voxels = 0;
  // The lattice and the improvement this case was built at (with the economical defaults
  // the mesh with the moves held keeps 9.94 degrees).
  o.volume.plc.grading = 1.0;
  o.volume.improve.insert_below_degrees = 50;
  o.volume.improve.insert_again_below_degrees = 40;
  PipelineOptions fixed = o;
  fixed.volume.improve.sheet_move_voxels = 0;
  o.output.dir = tmp.File("moved");
  fixed.output.dir = tmp.File("fixed");
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport moved, RunPipeline(o));
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport kept, RunPipeline(fixed));
  const VolumeMeshStats& m = *moved.volume_mesh;
  const VolumeMeshStats& k = *kept.volume_mesh;
  EXPECT_EQ(k.improvement.moved_sheet_vertices, 0u);
  // Both at the aim; which is higher varies with where the improvement's other operations
  // leave the mesh (11.16 degrees moved against 13.12 held since box triangles may be split;
  // within a degree of each other without that).
  EXPECT_GE(m.quality.min_dihedral.min, 10.0);
  EXPECT_GE(k.quality.min_dihedral.min, 10.0);
  EXPECT_LT(m.improvement.moved_sheet_vertices, 40u);
  EXPECT_LE(m.improvement.max_sheet_move, 1.0 + 1e-9);
  EXPECT_EQ(m.conformity.conforming, m.conformity.sheet_triangles);
  EXPECT_EQ(m.quality.inverted, 0u);
  ASSERT_TRUE(m.delivered_similarity.has_value() && k.delivered_similarity.has_value());
  EXPECT_GT(*m.delivered_similarity, *k.delivered_similarity - 0.02);
  // With the mends on (the default), the mesh holds its 10 degrees with the vertices held.
  PipelineOptions mended = fixed;
  mended.volume.plc.contact_voxels = PlcOptions().contact_voxels;
  mended.output.dir = tmp.File("mended");
  SM_ASSERT_OK_AND_ASSIGN(PipelineReport d, RunPipeline(mended));
  EXPECT_GE(d.volume_mesh->quality.min_dihedral.min, 10.0);
}

}  // namespace
}  // namespace sheetmesh
