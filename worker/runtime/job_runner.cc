#include "worker/runtime/job_runner.h"

#include <algorithm>
#include <filesystem>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_replace.h"
#include "common/file_util.h"
#include "common/progress.h"
#include "common/status_macros.h"
#include "worker/runtime/brick_tasks.h"
#include "worker/runtime/job_parameters.h"

namespace sheetmesh::runtime {
namespace {

// Forwards pipeline progress to the host as "stage k of n".
class HostObserver : public ProgressObserver {
 public:
  HostObserver(JobHost& host, std::string job, std::string worker, std::vector<std::string> stages)
      : host_(host), job_(std::move(job)), worker_(std::move(worker)), stages_(std::move(stages)) {}

  bool OnProgress(absl::string_view stage, double fraction, absl::string_view message) override {
    ProgressUpdate u;
    u.stage = std::string(stage);
    const auto it = std::find(stages_.begin(), stages_.end(), u.stage);
    u.stage_index = it == stages_.end() ? 0 : static_cast<int>(it - stages_.begin()) + 1;
    u.stage_count = static_cast<int>(stages_.size());
    u.fraction = fraction;
    u.message = std::string(message);
    return host_.ReportProgress(job_, worker_, u);
  }

 private:
  JobHost& host_;
  std::string job_, worker_;
  std::vector<std::string> stages_;
};

}  // namespace

std::string MediaTypeOf(const std::string& name) {
  if (absl::EndsWith(name, ".json")) return "application/json";
  if (absl::EndsWith(name, ".csv")) return "text/csv";
  if (absl::EndsWith(name, ".ply")) return "model/x-ply";
  if (absl::EndsWith(name, ".obj")) return "model/obj";
  if (absl::EndsWith(name, ".vtp") || absl::EndsWith(name, ".vtu"))
    return "application/vnd.vtk+xml";
  if (absl::EndsWith(name, ".msh")) return "model/x-gmsh";
  if (absl::EndsWith(name, ".inp")) return "text/x-abaqus-input";
  if (absl::EndsWith(name, ".png")) return "image/png";
  if (absl::EndsWith(name, ".exo")) return "application/x-netcdf";  // Exodus II is netCDF
  return "application/octet-stream";
}

namespace {

// Stores the outputs `files` of `job` (in `dir`) as its artifacts.
absl::StatusOr<std::vector<v1::Artifact>> StoreArtifacts(const v1::Job& job,
                                                         const std::string& worker, JobHost& host,
                                                         const std::string& dir,
                                                         const std::vector<std::string>& files) {
  std::vector<v1::Artifact> artifacts;
  for (const std::string& name : files) {
    if (name.find('/') != std::string::npos || name == ".." || name.empty()) {
      return absl::InternalError(absl::StrCat("the job named an output '", name, "'"));
    }
    SM_ASSIGN_OR_RETURN(v1::Artifact a,
                        host.PutArtifact(job.name(), worker, dir + "/" + name, MediaTypeOf(name)));
    a.set_name(name);
    artifacts.push_back(std::move(a));
  }
  return artifacts;
}

// The volume's name as the client gave it, without reading it (a merge reads none).
std::string InputName(const v1::JobInput& in) {
  if (!in.volume_path().empty()) return in.volume_path();
  if (!in.file_name().empty()) return in.file_name();
  if (in.has_volume_files()) return InputFolderName(in);
  return in.volume_digest().hash();
}

// The pipeline's outputs for `job` (or those of its brick task `task`): their names in `dir`.
absl::StatusOr<std::vector<std::string>> RunOutputs(const v1::Job& job, const std::string& worker,
                                                    JobHost& host, const JobRunOptions& run,
                                                    const std::string& dir,
                                                    const BrickTaskSpec& task) {
  // The job's options first (a bad parameter fails before any download), on the volume's
  // file name until the volume lies here.
  SM_ASSIGN_OR_RETURN(PipelineOptions options, JobPipelineOptions(job, InputFileName(job.input())));
  LocalVolume volume;
  if (task.task == "merge") {
    volume.path = volume.display_name = InputName(job.input());
  } else {
    // The bytes of the volume a brick or the plan reads, where the plan or the format names
    // them; the whole volume otherwise.
    std::optional<std::vector<ByteRange>> only;
    if (task.task == "brick") {
      SM_ASSIGN_OR_RETURN(only, BrickInputBytes(dir, task.index));
    } else if (task.task == "plan") {
      only = PlanInputBytes(options);
    }
    SM_ASSIGN_OR_RETURN(volume, host.ResolveInput(job, only ? &*only : nullptr));
  }
  options.input.path = volume.path;
  options.output.dir = dir;
  HostObserver observer(host, job.name(), worker,
                        task.task == "merge" || task.task.empty()
                            ? PlannedStages(options)
                            : std::vector<std::string>{"read"});
  std::vector<std::string> files;
  if (run.isolate) {
    SM_RETURN_IF_ERROR(MakeDirs(dir));
    JobSpec spec;
    spec.brick = task;
    spec.volume_path = volume.path;
    spec.display_name = volume.display_name;
    spec.output_dir = dir;
    spec.parameters = job.resolved_parameters();
    if (spec.parameters.empty()) {  // a job stored before parameters were resolved
      SM_ASSIGN_OR_RETURN(spec.parameters, ResolveJobParameters(job.parameters(), job.input()));
    }
    spec.data_files = volume.data_files;
    spec.allowed_roots = volume.data_file_roots;
    std::string program = run.program;
    if (program.empty()) {
      SM_ASSIGN_OR_RETURN(program, SelfPath());
    }
    // The job's own time limit, within the server's.
    JobLimits limits = run.limits;
    if (options.time_limit_seconds > 0) {
      limits.wall = std::min(limits.wall, absl::Seconds(options.time_limit_seconds));
    }
    SM_ASSIGN_OR_RETURN(files, RunJobInChild(program, spec, limits,
                                             [&](const std::string& stage, double fraction,
                                                 const std::string& message) {
                                               return observer.OnProgress(stage, fraction, message);
                                             }));
  } else {
    options.input.open.limits.confine_named_files = true;
    options.input.open.limits.named_file_roots =
        volume.data_files ? volume.data_file_roots : std::vector<std::string>{};
    if (!task.task.empty()) {
      return RunBrickTask(task, options, volume.display_name, Progress(&observer, "read"));
    }
    absl::StatusOr<PipelineReport> report = RunPipeline(options, Progress(&observer, "read"));
    if (!report.ok()) {
      // Name the volume the client knows, not the server's path for it; the files the run
      // kept stay named.
      if (!volume.display_name.empty() && volume.display_name != volume.path) {
        return WithKeptFiles(
            absl::Status(report.status().code(),
                         absl::StrReplaceAll(report.status().message(),
                                             {{volume.path, volume.display_name}})),
            KeptFiles(report.status()));
      }
      return report.status();
    }
    files = report->files;
  }
  return files;
}

// Which run `job` is: the whole pipeline, or a task of a job run as bricks.
BrickTaskSpec TaskOf(const v1::Job& job) {
  BrickTaskSpec t;
  const v1::JobBricks& b = job.bricks();
  if (!b.parent().empty()) {
    t.task = "brick";
    t.index = b.index();
  } else if (b.count() > 0) {
    t.task = "merge";
  } else if (!b.size().empty()) {
    t.task = "plan";
    t.brick_size = b.size();
  }
  return t;
}

// The plan, and for the merge every brick's output, fetched into the plan folder.
absl::Status FetchPlan(const v1::Job& job, JobHost& host, const std::string& dir,
                       const BrickTaskSpec& task) {
  const v1::JobBricks& b = job.bricks();
  SM_RETURN_IF_ERROR(MakeDirs(TaskPlanDir(dir) + "/bricks"));
  SM_RETURN_IF_ERROR(host.FetchBlob(b.plan().digest(), TaskPlanFile(dir)));
  if (task.task != "merge") return absl::OkStatus();
  if (b.outputs_size() != b.count()) {
    return absl::InternalError(absl::StrCat(job.name(), " came to be merged with ",
                                            b.outputs_size(), " of its ", b.count(),
                                            " bricks' outputs"));
  }
  for (int i = 0; i < b.outputs_size(); ++i) {
    SM_RETURN_IF_ERROR(host.FetchBlob(b.outputs(i).digest(), TaskBrickFile(dir, i)));
  }
  return absl::OkStatus();
}

// A task of a job run as bricks: the plan (then the job is split into its bricks) or a brick
// (its file the one artifact). The merge runs as a job does, with its plan fetched.
JobOutcome RunTask(const v1::Job& job, const std::string& worker, JobHost& host,
                   const JobRunOptions& run, const std::string& dir, const BrickTaskSpec& task) {
  JobOutcome outcome;
  outcome.status = [&]() -> absl::Status {
    if (task.task == "brick") SM_RETURN_IF_ERROR(FetchPlan(job, host, dir, task));
    // The files are where the task writes them; the child's list is not needed.
    SM_RETURN_IF_ERROR(RunOutputs(job, worker, host, run, dir, task).status());
    const bool plan = task.task == "plan";
    const std::string path = plan ? TaskPlanFile(dir) : TaskBrickFile(dir, task.index);
    SM_ASSIGN_OR_RETURN(v1::Artifact a,
                        host.PutArtifact(job.name(), worker, path, MediaTypeOf(path)));
    a.set_name(plan ? "plan.json" : absl::StrCat("brick_", task.index, ".bin"));
    if (!plan) {
      outcome.artifacts.push_back(std::move(a));
      return absl::OkStatus();
    }
    SM_ASSIGN_OR_RETURN(const int count, PlannedBricks(dir, kMaxJobBricks));
    SM_RETURN_IF_ERROR(host.Split(job.name(), worker, a, count));
    outcome.split = true;
    return absl::OkStatus();
  }();
  return outcome;
}

}  // namespace

JobOutcome RunJob(const v1::Job& job, const std::string& worker, JobHost& host,
                  const JobRunOptions& run) {
  const std::string dir =
      (std::filesystem::path(run.scratch_dir) / absl::StrReplaceAll(job.name(), {{"/", "-"}}))
          .string();
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  struct Cleanup {
    std::string dir;
    ~Cleanup() {
      std::error_code e;
      std::filesystem::remove_all(dir, e);
    }
  } cleanup{dir};
  JobOutcome outcome;
  const BrickTaskSpec task = TaskOf(job);
  if (task.task == "plan" || task.task == "brick")
    return RunTask(job, worker, host, run, dir, task);
  // The merge's bricks first.
  const absl::Status fetched =
      task.task == "merge" ? FetchPlan(job, host, dir, task) : absl::OkStatus();
  absl::StatusOr<std::vector<std::string>> files =
      fetched.ok() ? RunOutputs(job, worker, host, run, dir, task)
                   : absl::StatusOr<std::vector<std::string>>(fetched);
  std::vector<std::string> kept = files.ok() ? *files : KeptFiles(files.status());
  if (!files.ok()) {
    // The client knows no scratch folder: the kept files are the job's artifacts.
    outcome.status = absl::Status(
        files.status().code(),
        absl::StrReplaceAll(files.status().message(), {{"kept in " + dir, "kept as artifacts"}}));
  }
  absl::StatusOr<std::vector<v1::Artifact>> artifacts =
      StoreArtifacts(job, worker, host, dir, kept);
  if (!artifacts.ok()) {
    // A failed job keeps its error; a finished one fails storing its outputs.
    if (outcome.status.ok()) outcome.status = artifacts.status();
    return outcome;
  }
  outcome.artifacts = *std::move(artifacts);
  return outcome;
}

}  // namespace sheetmesh::runtime
