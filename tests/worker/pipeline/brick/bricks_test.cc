#include "worker/pipeline/brick/bricks.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "common/file_util.h"
#include "tests/testing/preset_sheets.h"
#include "tests/testing/status_matchers.h"
#include "tests/testing/temp_dir.h"
#include "worker/pipeline/phantom/phantom.h"
#include "worker/pipeline/phantom/phantom_presets.h"
#include "worker/pipeline/volume/nrrd_io.h"
#include "worker/pipeline/volume/raw_io.h"
#include "worker/pipeline/volume/tiff_io.h"
#include "worker/pipeline/volume/volume_open.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::StatusIs;
using ::sheetmesh::testing::TempDir;
using ::testing::HasSubstr;

// A preset's phantom at `dims`, as a raw file named with its dims.
std::string Phantom(const TempDir& tmp, const std::string& preset, const Dims& dims) {
  return ::sheetmesh::testing::PresetRawFile(tmp, preset, dims);
}

// A preset's phantom at `dims` written by `make_sink` (a reader's format).
template <class MakeSink>
void WritePhantom(const std::string& preset, const Dims& dims, MakeSink make_sink) {
  PhantomOptions o = *PhantomPreset(preset);
  o.dims = dims;
  PhantomTruth truth = *PlanPhantom(o);
  VolumeInfo info;
  info.dims = dims;
  auto sink = make_sink(info);
  ASSERT_TRUE(sink.ok()) << sink.status();
  ASSERT_TRUE(GeneratePhantom(&truth, **sink).ok());
}

// Plans `options` on `grid` in `dir`, runs every brick (in reverse order: any order will
// do) and returns the plan.
BrickPlan PlanAndRun(const PipelineOptions& options, const BrickGrid& grid,
                     const std::string& dir) {
  absl::StatusOr<BrickPlan> plan = MakeBrickPlan(options, grid);
  EXPECT_TRUE(plan.ok()) << plan.status();
  EXPECT_TRUE(WriteBrickPlan(*plan, dir).ok());
  for (int i = static_cast<int>(plan->bricks.size()) - 1; i >= 0; --i) {
    absl::StatusOr<BrickResult> r = RunBrick(dir, i);
    EXPECT_TRUE(r.ok()) << r.status();
  }
  return *plan;
}

// The report without what differs between two runs of one job (times, where it ran).
nlohmann::json Comparable(const std::string& report_path) {
  nlohmann::json j = nlohmann::json::parse(*ReadFileToString(report_path));
  std::function<void(nlohmann::json&)> strip = [&](nlohmann::json& v) {
    if (v.is_object()) {
      for (auto it = v.begin(); it != v.end();) {
        const std::string& k = it.key();
        if (k == "timings" || k == "seconds" || k == "path" || k == "dir" ||
            (k.size() > 8 && k.compare(k.size() - 8, 8, "_seconds") == 0)) {
          it = v.erase(it);
        } else {
          strip(*it);
          ++it;
        }
      }
    } else if (v.is_array()) {
      for (auto& x : v) strip(x);
    }
  };
  strip(j);
  return j;
}

TEST(BricksTest, TheJoinedPhaseIsTheVolumesWhateverTheBricksAndTheGridsOrigin) {
  TempDir tmp;
  for (const std::string& preset : {"shallow_network", "grazing_sheet", "vuggy_network"}) {
    PipelineOptions o;
    o.input.path = Phantom(tmp, preset, {61, 47, 53});
    const SheetPhase whole = *LoadSheetPhase(o.input);
    // Bricks of one voxel's width, smaller than a cell, uneven, and larger than the volume;
    // grids started at a corner and inside.
    const std::vector<BrickGrid> grids = {{{1, 47, 53}, {0, 0, 0}},
                                          {{7, 7, 7}, {3, 5, 2}},
                                          {{16, 9, 20}, {0, 4, 19}},
                                          {{33, 20, 50}, {0, 0, 0}},
                                          {{64, 64, 64}, {11, 0, 0}}};
    for (size_t g = 0; g < grids.size(); ++g) {
      const std::string dir = tmp.File(preset + "_plan" + std::to_string(g));
      const BrickPlan plan = PlanAndRun(o, grids[g], dir);
      VoxelSet::Builder joined(whole.sheet.dims());
      // The bricks' cores tile the box.
      int64_t covered = 0;
      for (const Brick& b : plan.bricks) covered += b.core.dims().num_voxels();
      EXPECT_EQ(covered, whole.info.dims.num_voxels());
      uint64_t voxels = 0;
      for (const Brick& b : plan.bricks) {
        absl::StatusOr<BrickResult> r = ReadBrick(dir, plan, b.index);
        ASSERT_TRUE(r.ok()) << r.status();
        voxels += r->sheet.size();
      }
      EXPECT_EQ(voxels, whole.sheet.size()) << preset << " grid " << g;
    }
  }
}

TEST(BricksTest, TheMergeGivesTheOneProcessRunsMeshAndReport) {
  TempDir tmp;
  PipelineOptions o;
  o.input.path = Phantom(tmp, "sample", {128, 112, 96});
  o.input.open.spacing = Vec3(5, 5, 6);
  o.input.open.unit = "um";
  o.surface.scvd.radius_voxels = 5;
  o.output.previews = false;
  PipelineOptions one = o;
  one.output.dir = tmp.File("one");
  ASSERT_TRUE(RunPipeline(one).ok());
  for (const BrickGrid& grid :
       {BrickGrid{{40, 50, 30}, {7, 0, 11}}, BrickGrid{{5, 128, 9}, {0, 0, 0}}}) {
    const std::string dir = tmp.File("plan" + std::to_string(grid.size.x));
    PlanAndRun(o, grid, dir);
    const std::string out = tmp.File("merged" + std::to_string(grid.size.x));
    MergeSummary summary;
    absl::StatusOr<PipelineReport> merged = MergeBricks(dir, out, {}, &summary);
    ASSERT_TRUE(merged.ok()) << merged.status();
    EXPECT_EQ(*ReadFileToString(out + "/surface.ply"),
              *ReadFileToString(one.output.dir + "/surface.ply"));
    EXPECT_EQ(ReadFileToString(out + "/model.vdb")->size(),
              ReadFileToString(one.output.dir + "/model.vdb")->size());
    EXPECT_EQ(Comparable(out + "/report.json"), Comparable(one.output.dir + "/report.json"));
    EXPECT_GT(summary.brick_bytes, 0u);
    const nlohmann::json bricks = nlohmann::json::parse(*ReadFileToString(out + "/bricks.json"));
    EXPECT_EQ(bricks["bricks"].get<int>(), summary.bricks);
  }
}

// The phantom as a noisy CT: rock about 170, the sheets about 70 (dark, open fractures),
// with a hashed noise of +-15.
void MakeGrey(const std::string& path) {
  std::string bytes = *ReadFileToString(path);
  for (size_t i = 0; i < bytes.size(); ++i) {
    uint64_t h = (i + 1) * 0x9E3779B97F4A7C15ULL;
    h ^= h >> 29;
    const int noise = static_cast<int>(h % 31) - 15;
    const int base = static_cast<uint8_t>(bytes[i]) ? 70 : 170;
    bytes[i] = static_cast<char>(base + noise);
  }
  ASSERT_TRUE(WriteFileAtomically(path, bytes).ok());
}

TEST(BricksTest, OtsusThresholdIsFoundByThePlanAndTheMergeIsTheOneProcesses) {
  TempDir tmp;
  PipelineOptions o;
  o.input.path = Phantom(tmp, "sample", {128, 112, 96});
  MakeGrey(o.input.path);
  o.input.threshold = "otsu";
  o.surface.scvd.radius_voxels = 5;
  o.output.previews = false;
  PipelineOptions one = o;
  one.output.dir = tmp.File("one");
  const absl::StatusOr<PipelineReport> ran = RunPipeline(one);
  ASSERT_TRUE(ran.ok()) << ran.status();
  const std::string dir = tmp.File("plan");
  const BrickPlan plan = PlanAndRun(o, {{40, 50, 30}, {7, 0, 11}}, dir);
  ASSERT_TRUE(plan.otsu.has_value());
  EXPECT_GT(*plan.otsu, 70);
  EXPECT_LT(*plan.otsu, 170);
  EXPECT_EQ(ReadBrickPlan(dir)->otsu, plan.otsu) << "kept in plan.json exactly";
  const std::string out = tmp.File("merged");
  ASSERT_TRUE(MergeBricks(dir, out).ok());
  EXPECT_EQ(*ReadFileToString(out + "/surface.ply"),
            *ReadFileToString(one.output.dir + "/surface.ply"));
  const nlohmann::json report = Comparable(out + "/report.json");
  EXPECT_EQ(report, Comparable(one.output.dir + "/report.json"));
  EXPECT_EQ(report["input"]["threshold"]["method"], "otsu");
  EXPECT_EQ(report["input"]["threshold"]["value"].get<double>(), *plan.otsu);
}

TEST(BricksTest, ABrickRunAgainWritesTheSameBytesAndAHalfWrittenOneDoesNotCount) {
  TempDir tmp;
  PipelineOptions o;
  o.input.path = Phantom(tmp, "sample", {128, 112, 96});
  const std::string dir = tmp.File("plan");
  ASSERT_TRUE(WriteBrickPlan(*MakeBrickPlan(o, {{64, 64, 64}, {0, 0, 0}}), dir).ok());
  ASSERT_TRUE(RunBrick(dir, 3).ok());
  const std::string first = *ReadFileToString(BrickFile(dir, 3));
  ASSERT_TRUE(RunBrick(dir, 3).ok());
  EXPECT_EQ(*ReadFileToString(BrickFile(dir, 3)), first);
  // A brick killed while writing leaves only its .part: the merge still misses it.
  for (int i = 0; i < 8; ++i) {
    if (i != 5) ASSERT_TRUE(RunBrick(dir, i).ok());
  }
  ASSERT_TRUE(WriteFileAtomically(BrickFile(dir, 5) + ".123-0.part", "half").ok());
  const std::string out = tmp.File("out");
  EXPECT_THAT(MergeBricks(dir, out).status(),
              StatusIs(absl::StatusCode::kFailedPrecondition, HasSubstr("(5)")));
  EXPECT_FALSE(std::filesystem::exists(out)) << "nothing is written before every brick is in";
  ASSERT_TRUE(RunBrick(dir, 5).ok());
  MergeSummary summary;
  EXPECT_TRUE(MergeBricks(dir, out, {}, &summary).ok());
  EXPECT_EQ(summary.stale_parts_removed, 1);
  EXPECT_FALSE(std::filesystem::exists(BrickFile(dir, 5) + ".123-0.part"));
}

TEST(BricksTest, ADamagedBrickOrOneOfAnotherPlanIsRefusedNamingItsFile) {
  TempDir tmp;
  PipelineOptions o;
  o.input.path = Phantom(tmp, "sample", {128, 112, 96});
  const std::string dir = tmp.File("plan");
  const BrickPlan plan = PlanAndRun(o, {{64, 64, 64}, {0, 0, 0}}, dir);
  std::string bytes = *ReadFileToString(BrickFile(dir, 2));
  bytes[bytes.size() / 2] ^= 0x5a;
  ASSERT_TRUE(WriteFileAtomically(BrickFile(dir, 2), bytes).ok());
  EXPECT_THAT(ReadBrick(dir, plan, 2).status(),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       ::testing::AllOf(HasSubstr("brick_000002.bin"), HasSubstr("checksum"))));
  EXPECT_THAT(MergeBricks(dir, tmp.File("out")).status(),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("brick_000002.bin")));
  EXPECT_FALSE(std::filesystem::exists(tmp.File("out/report.json")));
  // A brick of another plan (another selection) copied in.
  PipelineOptions other = o;
  other.input.selection = PhaseSelection::Labels({7});
  const std::string dir2 = tmp.File("plan2");
  PlanAndRun(other, {{64, 64, 64}, {0, 0, 0}}, dir2);
  std::filesystem::copy_file(BrickFile(dir2, 1), BrickFile(dir, 1),
                             std::filesystem::copy_options::overwrite_existing);
  EXPECT_THAT(ReadBrick(dir, plan, 1).status(),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("another plan")));
  // And a new plan in a folder that holds another's bricks.
  EXPECT_THAT(WriteBrickPlan(*MakeBrickPlan(other, {{64, 64, 64}, {0, 0, 0}}), dir),
              StatusIs(absl::StatusCode::kFailedPrecondition, HasSubstr("another plan")));
}

TEST(BricksTest, BadPlansAreRefusedNamingTheFieldAndValue) {
  TempDir tmp;
  PipelineOptions o;
  o.input.path = Phantom(tmp, "sample", {128, 112, 96});
  EXPECT_THAT(MakeBrickPlan(o, {{-1, 64, 64}, {0, 0, 0}}).status(),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("brick_size -1 along x")));
  // Chosen: slabs of whole slices.
  const BrickPlan slabs = *MakeBrickPlan(o, {});
  EXPECT_EQ(slabs.grid.size, (Index3{128, 112, 96}));  // the sample is under 2^27 voxels
  const BrickPlan thin = *MakeBrickPlan(o, {{0, 0, 10}, {0, 0, 0}});
  EXPECT_EQ(thin.bricks.size(), 10u);
  EXPECT_EQ(thin.bricks[9].core.dims(), (Dims{128, 112, 6}));
  EXPECT_THAT(MakeBrickPlan(o, {{64, 64, 64}, {0, 64, 0}}).status(),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("grid_origin 64 along y")));
  PipelineOptions grey = o;
  grey.grey.enabled = true;
  EXPECT_THAT(MakeBrickPlan(grey, {}).status(),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("input.grey")));
  const std::string dir = tmp.File("plan");
  ASSERT_TRUE(WriteBrickPlan(*MakeBrickPlan(o, {{64, 64, 64}, {0, 0, 0}}), dir).ok());
  EXPECT_THAT(RunBrick(dir, 8).status(),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       HasSubstr("brick index 8 is outside the plan's 8 bricks")));
  // A header that claims more voxels than its file holds.
  const std::string liar = tmp.File("liar_200x200x200_u8.raw");
  ASSERT_TRUE(WriteFileAtomically(liar, std::string(1000, '\1')).ok());
  PipelineOptions l = o;
  l.input.path = liar;
  EXPECT_THAT(MakeBrickPlan(l, {}).status(),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("liar_200x200x200_u8.raw")));
  // The volume cut short after planning: the brick names the file and what it lacks.
  ASSERT_TRUE(std::filesystem::remove(o.input.path));
  Phantom(tmp, "sample", {128, 112, 90});
  std::filesystem::rename(tmp.File("sample_128x112x90_u8.raw"), o.input.path);
  EXPECT_THAT(
      RunBrick(dir, 0).status(),
      StatusIs(absl::StatusCode::kInvalidArgument,
               ::testing::AllOf(HasSubstr("sample_128x112x96_u8.raw"), HasSubstr("truncated"))));
}

TEST(BricksTest, ARegionReadsItsBoxOfTheVolumeAndKeepsTheVolumesCoordinates) {
  TempDir tmp;
  const std::string path = Phantom(tmp, "sample", {128, 112, 96});
  OpenOptions whole_options;
  whole_options.spacing = Vec3(2, 3, 4);
  whole_options.origin = Vec3(10, 20, 30);
  auto whole = *OpenVolume(path, whole_options);
  const DenseVolume all = *ReadDense(*whole);
  OpenOptions o = whole_options;
  o.region = VoxelRegion{{5, 17, 30}, {70, 18, 91}};
  auto region = *OpenVolume(path, o);
  EXPECT_EQ(region->info().dims, (Dims{65, 1, 61}));
  EXPECT_EQ(region->info().placement.origin, Vec3(20, 71, 150));
  const DenseVolume part = *ReadDense(*region);
  int64_t differ = 0;
  for (int64_t z = 0; z < 61; ++z) {
    for (int64_t x = 0; x < 65; ++x) differ += part.At(x, 0, z) != all.At(x + 5, 17, z + 30);
  }
  EXPECT_EQ(differ, 0);
  o.region = VoxelRegion{{5, 17, 30}, {70, 18, 97}};
  EXPECT_THAT(OpenVolume(path, o).status(),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       ::testing::AllOf(HasSubstr("input.region 5,17,30,70,18,97"),
                                        HasSubstr("outside the volume along z"))));
}

TEST(BricksTest, AStackWithAMissingSliceIsRefusedNamingIt) {
  TempDir tmp;
  const std::string folder = tmp.File("stack");
  std::filesystem::create_directories(folder);
  VolumeInfo info;
  info.dims = {8, 6, 1};
  for (int z = 0; z < 10; ++z) {
    if (z == 6) continue;
    auto sink = *CreateTiffWriter(folder + "/scan_" + std::to_string(1000 + z) + ".tif", info);
    std::vector<std::byte> slice(48, std::byte{1});
    ASSERT_TRUE(sink->WriteSlices(1, slice).ok());
    ASSERT_TRUE(sink->Finish().ok());
  }
  PipelineOptions o;
  o.input.path = folder;
  EXPECT_THAT(MakeBrickPlan(o, {}).status(),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       ::testing::AllOf(HasSubstr("slice number 1006 is missing"),
                                        HasSubstr("scan_1005.tif"), HasSubstr("scan_1007.tif"))));
}

}  // namespace
}  // namespace sheetmesh

namespace sheetmesh {
namespace {

// A copy of `path` at `copy` as large, holding only `ranges` (clipped to the file) and
// zeros elsewhere: what a worker that fetched those bytes only has.
void CopyRangesOnly(const std::string& path, const std::vector<FileRange>& ranges,
                    const std::string& copy) {
  const std::string whole = *ReadFileToString(path);
  std::string only(whole.size(), '\0');
  for (const FileRange& r : ranges) {
    const int64_t end = std::min<int64_t>(r.offset + r.length, whole.size());
    if (r.offset < end) only.replace(r.offset, end - r.offset, whole, r.offset, end - r.offset);
  }
  ASSERT_TRUE(MakeDirs(std::filesystem::path(copy).parent_path().string()).ok());
  ASSERT_TRUE(WriteFileAtomically(copy, only).ok());
}

TEST(BricksTest, ABrickOfARawOrNrrdFileReadsOnlyTheBytesItsPlanNames) {
  TempDir tmp;
  const Dims dims{128, 112, 96};
  const std::string raw = tmp.File("v/sample_128x112x96_u8.raw");
  const std::string nrrd = tmp.File("v/sample.nrrd");
  ASSERT_TRUE(MakeDirs(tmp.File("v")).ok());
  WritePhantom("sample", dims, [&](const VolumeInfo& i) { return CreateRawWriter(raw, i); });
  WritePhantom("sample", dims, [&](const VolumeInfo& i) { return CreateNrrdWriter(nrrd, i); });
  for (const std::string& volume : {raw, nrrd}) {
    for (const BrickGrid& grid :
         {BrickGrid{{0, 0, 20}, {0, 0, 0}}, BrickGrid{{48, 40, 32}, {7, 0, 5}}}) {
      SCOPED_TRACE(volume + " in bricks of " + std::to_string(grid.size.z) + " slices");
      PipelineOptions o;
      o.input.path = volume;
      const std::string dir = tmp.File("plan");
      std::filesystem::remove_all(dir);
      const BrickPlan plan = PlanAndRun(o, grid, dir);
      const int64_t size = static_cast<int64_t>(std::filesystem::file_size(volume));
      for (const Brick& b : plan.bricks) {
        ASSERT_FALSE(b.fetch.empty()) << "brick " << b.index;
        int64_t fetched = 0;
        for (const FileRange& r : b.fetch) fetched += std::min(r.length, size - r.offset);
        EXPECT_LT(fetched, size) << "brick " << b.index << " fetches the whole file";
        const std::string full = *ReadFileToString(BrickFile(dir, b.index));
        // The same brick on a file holding only those bytes.
        const std::string only =
            tmp.File("only/" + std::filesystem::path(volume).filename().string());
        CopyRangesOnly(volume, b.fetch, only);
        BrickSite site;
        site.volume = only;
        ASSERT_TRUE(RunBrick(dir, b.index, {}, site).ok()) << "brick " << b.index;
        EXPECT_EQ(*ReadFileToString(BrickFile(dir, b.index)), full) << "brick " << b.index;
      }
    }
  }
  // A reader that may read any of its file names no bytes: the worker fetches it whole.
  const std::string tif = tmp.File("sample.tif");
  WritePhantom("sample", dims, [&](const VolumeInfo& i) { return CreateTiffWriter(tif, i); });
  PipelineOptions o;
  o.input.path = tif;
  const absl::StatusOr<BrickPlan> plan = MakeBrickPlan(o, {{0, 0, 32}, {0, 0, 0}});
  ASSERT_TRUE(plan.ok()) << plan.status();
  for (const Brick& b : plan->bricks) EXPECT_TRUE(b.fetch.empty());
  // And the plan says it in plan.json, and reads it back.
  const std::string dir = tmp.File("plan2");
  o.input.path = raw;
  ASSERT_TRUE(WriteBrickPlan(*MakeBrickPlan(o, {{0, 0, 32}, {0, 0, 0}}), dir).ok());
  const absl::StatusOr<BrickPlan> back = ReadBrickPlan(dir);
  ASSERT_TRUE(back.ok()) << back.status();
  ASSERT_EQ(back->bricks.size(), 3u);
  EXPECT_EQ(back->bricks[1].fetch, (std::vector<FileRange>{{32 * 128 * 112, 32 * 128 * 112}}));
}

}  // namespace
}  // namespace sheetmesh

namespace sheetmesh {
namespace {

// Hardening, third round: a plan edited to 1048576^3 voxels in bricks of 1 made the merge
// throw std::bad_alloc (its row table). A plan is checked whole when read, and the planner
// refuses grids of more than kMaxPlanBricks bricks.
TEST(BricksTest, APlansSizesAreCheckedBeforeAnythingIsSizedFromThem) {
  TempDir tmp;
  PipelineOptions o;
  o.input.path = Phantom(tmp, "sample", {64, 56, 48});
  const std::string dir = tmp.File("plan");
  ASSERT_TRUE(WriteBrickPlan(*MakeBrickPlan(o, {{32, 32, 32}, {0, 0, 0}}), dir).ok());
  ASSERT_TRUE(ReadBrickPlan(dir).ok());
  const std::string text = *ReadFileToString(PlanFile(dir));
  const auto edited = [&](const std::function<void(nlohmann::json&)>& edit) {
    nlohmann::json j = nlohmann::json::parse(text);
    edit(j);
    EXPECT_TRUE(WriteFileAtomically(PlanFile(dir), j.dump()).ok());
    return ReadBrickPlan(dir).status();
  };
  EXPECT_THAT(edited([](nlohmann::json& j) {
                j["dims"] = {1048576, 1048576, 1048576};
                j["brick_size"] = {1, 1, 1};
              }),
              StatusIs(absl::StatusCode::kResourceExhausted,
                       ::testing::AllOf(HasSubstr("plan.json: dims"), HasSubstr("1048576"))));
  EXPECT_THAT(edited([](nlohmann::json& j) {
                j["brick_size"] = {1, 1, 1};
              }),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("more than 65536 bricks")));
  EXPECT_THAT(edited([](nlohmann::json& j) {
                j["dims"] = {64, 56, 96};
              }),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("bricks[4]")));
  EXPECT_THAT(edited([](nlohmann::json& j) { j["bricks"].erase(j["bricks"].size() - 1); }),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("7 bricks hold")));
  EXPECT_THAT(edited([](nlohmann::json& j) { j["bricks"][1]["core"] = {0, 0, 0, 32, 32, 32}; }),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("bricks[1]")));
  EXPECT_THAT(
      edited([](nlohmann::json& j) { j["bricks"][0]["core"] = {0, 0, 0, 33, 32, 32}; }),
      StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("not a cell of the plan's grid")));
  EXPECT_THAT(MakeBrickPlan(o, {{1, 1, 1}, {0, 0, 0}}).status(),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("more than 65536 bricks")));
}

}  // namespace
}  // namespace sheetmesh
