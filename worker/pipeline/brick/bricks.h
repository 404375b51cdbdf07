// Bricks: one volume cut into boxes that separate processes (cluster array tasks, the
// service's workers) read at once, each writing a small file of its own, and a merge that
// joins them and runs the rest of the job.
//
// Stage chain of this version: a brick reads its box (only that box's slices, input.region)
// and selects the sheet phase there; the merge joins the bricks' sheet voxels into the
// volume's sparse sheet set and runs every later stage on it in one process
// (RunPipelineOnPhase). Selection is per voxel, so a brick needs no halo and the merge's
// set is the set one process reads, voxel for voxel: the result is the same, whatever the
// brick size or the grid's origin. What the merge holds follows the sheets, not the box.
//
//   sheetmesh-pipeline plan VOLUME --brick_size=512 -o PLAN  (plus the job's parameters)
//   sheetmesh-pipeline brick PLAN --index=I                  (I = 0 .. count - 1, any order,
//                                                             anywhere the files are seen)
//   sheetmesh-pipeline merge PLAN -o OUT
#ifndef SHEETMESH_WORKER_PIPELINE_BRICK_BRICKS_H_
#define SHEETMESH_WORKER_PIPELINE_BRICK_BRICKS_H_

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/run/pipeline.h"
#include "worker/pipeline/volume/volume_open.h"

namespace sheetmesh {

// How to cut: brick edges per axis, and where the grid starts (a brick corner, in voxels;
// bricks along an axis start at origin - k * size, clipped to the volume). An edge of 0 is
// chosen: x and y the whole volume's, z so that a brick holds about kAutoBrickVoxels.
// Every reader reads slices, and raw files lie slice after slice: such slabs read each byte
// of the file once, where cubes of a file larger than memory read it again for every brick
// along x (bench/RESULTS.md).
struct BrickGrid {
  Index3 size{0, 0, 0};
  Index3 origin{0, 0, 0};
};
inline constexpr int64_t kAutoBrickVoxels = int64_t{1} << 27;

// The most bricks a plan may hold (a job's are bounded further by its server).
inline constexpr int64_t kMaxPlanBricks = int64_t{1} << 16;

// kInvalidArgument naming `what` when `grid` cuts a volume of `dims` into more than
// kMaxPlanBricks bricks, or has an edge below 1.
absl::Status CheckBrickCount(const Dims& dims, const BrickGrid& grid, absl::string_view what);

// BrickGrid::size from "auto" (every edge chosen), "512" or "512x512x256";
// kInvalidArgument naming `field` and the text otherwise.
absl::StatusOr<Index3> ParseBrickSize(const std::string& text, const std::string& field);

struct Brick {
  int index = 0;
  VoxelRegion core;  // the voxels this brick owns (and writes)
  VoxelRegion read;  // what it reads: the core and its halo, clipped to the volume
  // The bytes of the volume's file it reads, sorted and apart (VolumeSource::BytesRead),
  // where the reader tells them; empty: any of it. A worker that fetches the volume from
  // elsewhere fetches these only.
  std::vector<FileRange> fetch;
};

struct BrickPlan {
  std::string volume;      // the volume's path (absolute)
  std::string parameters;  // the job's parameters, canonical JSON (CanonicalParametersJson)
  VolumeInfo info;         // the volume's, as opened
  BrickGrid grid;
  // With input.threshold = otsu: Otsu's threshold of the whole volume, found by the plan
  // (one pass over the file, a histogram's memory) so that every brick selects alike.
  std::optional<double> otsu;
  int halo = 0;                        // voxels around each core a brick reads besides it
  std::vector<std::string> in_bricks;  // the stages bricks run ("read", "select")
  std::vector<Brick> bricks;
  uint64_t fingerprint = 0;  // of plan.json's text (each brick file carries it)

  std::string ToJson() const;
};

// The plan of `options`'s job (options.input names the volume) on `grid`. kInvalidArgument
// naming the field and value for a brick size below 0 or below twice the halo, an origin
// outside [0, size), options the bricks cannot run (input.grey, input.region), and the
// reader's errors. A threshold of "otsu" is found here, reading the whole volume once.
absl::StatusOr<BrickPlan> MakeBrickPlan(const PipelineOptions& options, const BrickGrid& grid);

// The bytes of options.input.path's file that MakeBrickPlan reads, where its format tells
// them before the file is opened: none of a raw file (its size is all), the head of an NRRD
// file (kNrrdMaxHeaderBytes); nullopt: any (other formats, and a threshold of "otsu", which
// reads every voxel). What a worker fetches of a volume it plans but does not hold.
std::optional<std::vector<FileRange>> PlanReads(const PipelineOptions& options);

// The plan folder's files: plan.json, and bricks/brick_<index>.bin.
std::string PlanFile(const std::string& plan_dir);
std::string BrickFile(const std::string& plan_dir, int index);

// Writes plan.json into `plan_dir` (made if missing). A folder holding another plan's
// bricks is refused (kFailedPrecondition), so that no merge mixes two plans.
absl::Status WriteBrickPlan(const BrickPlan& plan, const std::string& plan_dir);
// Reads plan.json back. kInvalidArgument naming the file and field when it is not a plan.
absl::StatusOr<BrickPlan> ReadBrickPlan(const std::string& plan_dir);

// What one brick found.
struct BrickResult {
  int index = 0;
  VoxelRegion core;
  uint64_t plan_hash = 0;   // of the plan.json it ran from
  VoxelSet sheet;           // the core's sheet voxels, in the core's coordinates
  SelectionStats stats;     // of the brick's box
  uint64_t file_bytes = 0;  // of its file
};

// Where a brick or a merge runs, when not where the plan was made (a service's worker, which
// sees the volume under its own path and reads it within the job's limits).
struct BrickSite {
  std::string volume;                  // the volume's path here ("": the plan's)
  std::optional<VolumeLimits> limits;  // what its reader may do (unset: the defaults)
  std::string plan_name;               // the plan in bricks.json ("": its absolute path)
  ChildReaderOptions child_reader;     // how its reader runs (default: in this process)
};

// Runs brick `index` of the plan in `plan_dir` and writes its file atomically (a brick killed
// mid-run leaves none; run again, it writes the same bytes). kInvalidArgument for an index
// outside the plan (naming it and the count); the reader's errors name the file.
absl::StatusOr<BrickResult> RunBrick(const std::string& plan_dir, int index,
                                     const Progress& progress = {}, const BrickSite& site = {});

// Reads brick `index`'s file. kNotFound when it has not run; kInvalidArgument (naming the
// file) when it is damaged or belongs to another plan.
absl::StatusOr<BrickResult> ReadBrick(const std::string& plan_dir, const BrickPlan& plan,
                                      int index);

struct MergeSummary {
  int bricks = 0;
  uint64_t brick_bytes = 0;  // the bricks' files, in all
  uint64_t sheet_voxels = 0;
  double join_seconds = 0;      // reading and joining the bricks
  int stale_parts_removed = 0;  // half-written files of killed bricks, removed
};

// Joins every brick of the plan in `plan_dir` into the volume's sheet phase and runs the job
// on it with its outputs in `output_dir` (plus bricks.json); removes what killed bricks left
// half-written. kFailedPrecondition naming the bricks that have not run (nothing is written
// then); the job's errors pass through.
absl::StatusOr<PipelineReport> MergeBricks(const std::string& plan_dir,
                                           const std::string& output_dir,
                                           const Progress& progress = {},
                                           MergeSummary* summary = nullptr,
                                           const BrickSite& site = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_BRICK_BRICKS_H_
