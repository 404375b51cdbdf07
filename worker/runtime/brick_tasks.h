// A job run as bricks (JobBricks in jobs.proto), the worker's side: the three tasks a job's
// child runs besides the whole pipeline. In a job's scratch folder `dir` the plan lies in
// dir/plan (plan.json, bricks/brick_<i>.bin) and the merge writes the job's outputs in dir.
#ifndef SHEETMESH_WORKER_RUNTIME_BRICK_TASKS_H_
#define SHEETMESH_WORKER_RUNTIME_BRICK_TASKS_H_

#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/run/pipeline.h"
#include "worker/runtime/job_host.h"

namespace sheetmesh::runtime {

// What a job's run is: the whole pipeline, or one task of a job run as bricks.
struct BrickTaskSpec {
  std::string task;        // "" (the whole pipeline), "plan", "brick" or "merge"
  std::string brick_size;  // plan: JobBricks.size
  int index = 0;           // brick: its index in the plan
};

// dir/plan, dir/plan/plan.json, dir/plan/bricks/brick_<index>.bin.
std::string TaskPlanDir(const std::string& dir);
std::string TaskPlanFile(const std::string& dir);
std::string TaskBrickFile(const std::string& dir, int index);

// Runs `spec`'s task with the job's `options` (options.input.path: the volume here, read
// within options.input.open.limits; options.output.dir: the scratch folder) and returns the
// files it wrote, as paths within that folder: the plan (plan/plan.json, where the volume is
// named `display`, the name the client knows), a brick's file, or the merged job's outputs
// and bricks.json.
absl::StatusOr<std::vector<std::string>> RunBrickTask(const BrickTaskSpec& spec,
                                                      PipelineOptions options,
                                                      const std::string& display,
                                                      const Progress& progress);

// The bytes of the volume's file brick `index` of the plan in dir/plan reads (Brick::fetch),
// for a host that fetches the volume from elsewhere; nullopt when the plan names none (the
// reader may read any of the file: fetch it whole). The plan's errors as PlannedBricks's.
absl::StatusOr<std::optional<std::vector<ByteRange>>> BrickInputBytes(const std::string& dir,
                                                                      int index);

// The bytes of the volume a plan task with the job's `options` reads (PlanReads); nullopt:
// any of it.
std::optional<std::vector<ByteRange>> PlanInputBytes(const PipelineOptions& options);

// The number of bricks of the plan in dir/plan. kInvalidArgument when it has more than
// `max` (the message says to ask for larger bricks).
absl::StatusOr<int> PlannedBricks(const std::string& dir, int max);

}  // namespace sheetmesh::runtime

#endif  // SHEETMESH_WORKER_RUNTIME_BRICK_TASKS_H_
