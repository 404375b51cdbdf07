// The merge: the bricks' sheet voxels joined layer of bricks by layer (only one layer's
// bricks in memory besides the set being built), then the job on the joined phase.
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/time/clock.h"
#include "common/file_util.h"
#include "common/status_macros.h"
#include "worker/pipeline/brick/bricks.h"
#include "worker/pipeline/run/parameters.h"

namespace sheetmesh {
namespace {

// The bricks that have not run, as the message lists them: "3, 7 and 12 others".
std::string MissingText(const std::vector<int>& missing) {
  std::vector<int> shown(missing.begin(), missing.begin() + std::min<size_t>(10, missing.size()));
  std::string s = absl::StrJoin(shown, ", ");
  if (missing.size() > shown.size())
    absl::StrAppend(&s, " and ", missing.size() - shown.size(), " more");
  return s;
}

}  // namespace

absl::StatusOr<PipelineReport> MergeBricks(const std::string& plan_dir,
                                           const std::string& output_dir, const Progress& progress,
                                           MergeSummary* summary, const BrickSite& site) {
  const absl::Time start = absl::Now();
  SM_ASSIGN_OR_RETURN(BrickPlan plan, ReadBrickPlan(plan_dir));
  if (!site.volume.empty()) plan.volume = site.volume;
  // Every brick present before anything is written.
  std::vector<int> missing;
  for (const Brick& b : plan.bricks) {
    std::error_code ec;
    if (!std::filesystem::exists(BrickFile(plan_dir, b.index), ec)) missing.push_back(b.index);
  }
  if (!missing.empty()) {
    return absl::FailedPreconditionError(absl::StrCat(
        missing.size(), " of the plan's ", plan.bricks.size(), " bricks have not run (",
        MissingText(missing), "): run them (sheetmesh-pipeline brick ", plan_dir,
        " --index=I), then merge; nothing was written"));
  }
  ParameterBuilder builder;
  SM_RETURN_IF_ERROR(builder.AddJson(plan.parameters, PlanFile(plan_dir)));
  SM_ASSIGN_OR_RETURN(PipelineOptions options, builder.Build());
  options.input.path = plan.volume;
  options.output.dir = output_dir;

  // Bricks by layer along z, then by row of bricks along y, then along x.
  std::map<int32_t, std::vector<const Brick*>> layers;
  for (const Brick& b : plan.bricks) layers[b.core.lo.z].push_back(&b);
  const Dims& d = plan.info.dims;
  // The joined set's row table: a word a row of the volume, before any voxel.
  SM_RETURN_IF_ERROR(CheckAllocation(
      (d.num_rows() + 1) * int64_t{sizeof(int64_t)},
      site.limits ? *site.limits : VolumeLimits{},
      absl::StrCat(PlanFile(plan_dir), ": the row table of its ", d.ToString(), " volume")));
  VoxelSet::Builder joined(d);
  SheetPhase phase;
  phase.info = plan.info;
  phase.info.path = plan.volume;
  SelectionStats& stats = phase.stats;
  stats.min_value = std::numeric_limits<double>::infinity();
  stats.max_value = -std::numeric_limits<double>::infinity();
  MergeSummary sum;
  int done = 0;
  for (const auto& [z0, bricks] : layers) {
    std::vector<BrickResult> layer;
    for (const Brick* b : bricks) {
      SM_ASSIGN_OR_RETURN(BrickResult r, ReadBrick(plan_dir, plan, b->index));
      sum.brick_bytes += r.file_bytes;
      stats.min_value = std::min(stats.min_value, r.stats.min_value);
      stats.max_value = std::max(stats.max_value, r.stats.max_value);
      stats.selected += r.stats.selected;
      stats.outside_mask += r.stats.outside_mask;
      layer.push_back(std::move(r));
    }
    // Rows in (z, y) order; within a row the bricks in x order (the plan lists them so).
    const int32_t z1 = layer.front().core.hi.z;
    for (int32_t z = z0; z < z1; ++z) {
      for (int32_t y = 0; y < d.ny; ++y) {
        for (const BrickResult& r : layer) {
          if (y < r.core.lo.y || y >= r.core.hi.y) continue;
          for (const Run& run : r.sheet.RowRuns(y - r.core.lo.y, z - r.core.lo.z)) {
            joined.AddRun(y, z, run.x0 + r.core.lo.x, run.x1 + r.core.lo.x);
          }
        }
      }
    }
    done += static_cast<int>(layer.size());
    SM_RETURN_IF_ERROR(progress.Stage("read").Update(double(done) / plan.bricks.size(),
                                                     absl::StrCat(done, " bricks joined")));
  }
  phase.sheet = std::move(joined).Build();
  // What killed bricks left half-written: every brick is in, so no .part is needed.
  {
    std::error_code ec;
    for (const auto& e :
         std::filesystem::directory_iterator(std::filesystem::path(plan_dir) / "bricks", ec)) {
      if (e.path().extension() == ".part" && std::filesystem::remove(e.path(), ec)) {
        ++sum.stale_parts_removed;
      }
    }
  }
  SM_ASSIGN_OR_RETURN(phase.selection, StatedSelection(options.input, &phase.threshold, plan.otsu));
  SM_RETURN_IF_ERROR(CheckSheetPhase(options.input, phase));
  sum.bricks = static_cast<int>(plan.bricks.size());
  sum.sheet_voxels = phase.sheet.size();
  sum.join_seconds = absl::ToDoubleSeconds(absl::Now() - start);
  phase.read_seconds = sum.join_seconds;
  SM_ASSIGN_OR_RETURN(PipelineReport report,
                      RunPipelineOnPhase(options, std::move(phase), progress));
  if (!output_dir.empty()) {
    nlohmann::json j = {
        {"plan", site.plan_name.empty() ? std::filesystem::absolute(PlanFile(plan_dir)).string()
                                        : site.plan_name},
        {"bricks", sum.bricks},
        {"brick_size", {plan.grid.size.x, plan.grid.size.y, plan.grid.size.z}},
        {"grid_origin", {plan.grid.origin.x, plan.grid.origin.y, plan.grid.origin.z}},
        {"halo", plan.halo},
        {"in_bricks", plan.in_bricks},
        {"brick_bytes", sum.brick_bytes},
        {"sheet_voxels", sum.sheet_voxels},
        {"join_seconds", sum.join_seconds}};
    SM_RETURN_IF_ERROR(WriteFileAtomically(
        (std::filesystem::path(output_dir) / "bricks.json").string(), j.dump(1) + "\n"));
  }
  if (summary != nullptr) *summary = sum;
  return report;
}

}  // namespace sheetmesh
