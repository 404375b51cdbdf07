#include "worker/runtime/job_runner.h"

#include <algorithm>
#include <filesystem>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_replace.h"
#include "common/progress.h"
#include "common/status_macros.h"
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
  return "application/octet-stream";
}

absl::StatusOr<std::vector<v1::Artifact>> RunJob(const v1::Job& job, const std::string& worker,
                                                 JobHost& host, const std::string& scratch_dir) {
  SM_ASSIGN_OR_RETURN(LocalVolume volume, host.ResolveInput(job));
  SM_ASSIGN_OR_RETURN(PipelineOptions options, JobPipelineOptions(job, volume.path));
  const std::string dir =
      (std::filesystem::path(scratch_dir) / absl::StrReplaceAll(job.name(), {{"/", "-"}})).string();
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  options.output.dir = dir;
  HostObserver observer(host, job.name(), worker, PlannedStages(options));
  absl::StatusOr<PipelineReport> report = RunPipeline(options, Progress(&observer, "read"));
  struct Cleanup {
    std::string dir;
    ~Cleanup() {
      std::error_code e;
      std::filesystem::remove_all(dir, e);
    }
  } cleanup{dir};
  if (!report.ok()) {
    // Name the volume the client knows, not the server's path for it.
    if (!volume.display_name.empty() && volume.display_name != volume.path) {
      return absl::Status(
          report.status().code(),
          absl::StrReplaceAll(report.status().message(), {{volume.path, volume.display_name}}));
    }
    return report.status();
  }
  std::vector<v1::Artifact> artifacts;
  for (const std::string& name : report->files) {
    SM_ASSIGN_OR_RETURN(v1::Artifact a,
                        host.PutArtifact(job.name(), dir + "/" + name, MediaTypeOf(name)));
    a.set_name(name);
    artifacts.push_back(std::move(a));
  }
  return artifacts;
}

}  // namespace sheetmesh::runtime
