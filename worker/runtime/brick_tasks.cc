#include "worker/runtime/brick_tasks.h"

#include <filesystem>

#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "worker/pipeline/brick/bricks.h"

namespace sheetmesh::runtime {

std::string TaskPlanDir(const std::string& dir) { return dir + "/plan"; }
std::string TaskPlanFile(const std::string& dir) { return PlanFile(TaskPlanDir(dir)); }
std::string TaskBrickFile(const std::string& dir, int index) {
  return BrickFile(TaskPlanDir(dir), index);
}

absl::StatusOr<std::vector<std::string>> RunBrickTask(const BrickTaskSpec& spec,
                                                      PipelineOptions options,
                                                      const std::string& display,
                                                      const Progress& progress) {
  const std::string dir = options.output.dir;
  if (spec.task == "plan") {
    BrickGrid grid;
    SM_ASSIGN_OR_RETURN(grid.size, ParseBrickSize(spec.brick_size, "bricks"));
    SM_ASSIGN_OR_RETURN(BrickPlan plan, MakeBrickPlan(options, grid));
    plan.volume = display;  // each worker reads the volume where it sees it
    SM_RETURN_IF_ERROR(WriteBrickPlan(plan, TaskPlanDir(dir)));
    return std::vector<std::string>{TaskPlanFile(dir).substr(dir.size() + 1)};
  }
  BrickSite site;
  site.volume = options.input.path;
  site.limits = options.input.open.limits;
  if (spec.task == "brick") {
    SM_RETURN_IF_ERROR(RunBrick(TaskPlanDir(dir), spec.index, progress, site).status());
    return std::vector<std::string>{TaskBrickFile(dir, spec.index).substr(dir.size() + 1)};
  }
  if (spec.task == "merge") {
    site.volume = display;  // the merge reads no volume: the name is for its messages
    site.plan_name = "plan.json (the job's bricks.plan)";
    SM_ASSIGN_OR_RETURN(PipelineReport report,
                        MergeBricks(TaskPlanDir(dir), dir, progress, nullptr, site));
    std::vector<std::string> files = report.files;
    files.push_back("bricks.json");
    return files;
  }
  return absl::InvalidArgumentError(absl::StrCat("'", spec.task, "' is not a brick task"));
}

namespace {

// The plan in dir/plan, read back in this process: the job's child wrote it, having read the
// volume, so it may hold at most what `max` bricks take.
absl::StatusOr<BrickPlan> ReadTaskPlan(const std::string& dir, int max) {
  std::error_code ec;
  const uintmax_t bytes = std::filesystem::file_size(TaskPlanFile(dir), ec);
  const uintmax_t most = 4096 + uintmax_t{1024} * static_cast<uintmax_t>(max);
  if (ec || bytes > most) {
    return absl::InternalError(absl::StrCat(
        "the job's plan (plan.json) ",
        ec ? ec.message()
           : absl::StrCat("holds ", bytes, " bytes, more than ", most, " for ", max, " bricks")));
  }
  return ReadBrickPlan(TaskPlanDir(dir));
}

std::vector<ByteRange> ByteRangesOf(const std::vector<FileRange>& ranges) {
  std::vector<ByteRange> out;
  for (const FileRange& r : ranges) out.push_back({r.offset, r.length});
  return out;
}

}  // namespace

absl::StatusOr<int> PlannedBricks(const std::string& dir, int max) {
  SM_ASSIGN_OR_RETURN(const BrickPlan plan, ReadTaskPlan(dir, max));
  const int64_t n = static_cast<int64_t>(plan.bricks.size());
  if (n > max) {
    return absl::InvalidArgumentError(
        absl::StrCat("bricks: the plan cuts ", plan.info.dims.ToString(), " into ", n,
                     " bricks, more than the ", max, " one job may have: ask for larger bricks"));
  }
  return static_cast<int>(n);
}

std::optional<std::vector<ByteRange>> PlanInputBytes(const PipelineOptions& options) {
  const std::optional<std::vector<FileRange>> reads = PlanReads(options);
  if (!reads) return std::nullopt;
  return ByteRangesOf(*reads);
}

absl::StatusOr<std::optional<std::vector<ByteRange>>> BrickInputBytes(const std::string& dir,
                                                                      int index) {
  SM_ASSIGN_OR_RETURN(const BrickPlan plan, ReadTaskPlan(dir, kMaxJobBricks));
  if (index < 0 || index >= static_cast<int>(plan.bricks.size())) {
    return absl::InvalidArgumentError(absl::StrCat("brick index ", index, " is outside the plan's ",
                                                   plan.bricks.size(), " bricks"));
  }
  const Brick& b = plan.bricks[static_cast<size_t>(index)];
  if (b.fetch.empty()) return std::optional<std::vector<ByteRange>>();
  return std::optional<std::vector<ByteRange>>(ByteRangesOf(b.fetch));
}

}  // namespace sheetmesh::runtime
