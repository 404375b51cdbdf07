#include "worker/runtime/job_process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <new>
#include <nlohmann/json.hpp>
#include <optional>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_replace.h"
#include "common/file_util.h"
#include "common/json_text.h"
#include "common/machine.h"
#include "common/status_macros.h"
#include "common/subprocess.h"
#include "worker/pipeline/run/parameters.h"
#include "worker/pipeline/run/pipeline.h"
#include "worker/pipeline/volume/volume_open.h"
#include "worker/runtime/brick_tasks.h"
#include "worker/runtime/sandbox.h"

namespace sheetmesh::runtime {
namespace {

using Json = nlohmann::json;

constexpr char kChildFlag[] = "--sheetmesh-job-child";
constexpr int kReportFd = 3;

std::string Bytes(uint64_t b) {
  if (b >= (uint64_t{1} << 30)) return absl::StrFormat("%.3g GiB", double(b) / (1 << 30));
  return absl::StrFormat("%.3g MiB", double(b) / (1 << 20));
}

// --- The child ---------------------------------------------------------------------------

// Writes one JSON line to the parent. A parent that is gone (EPIPE) ends the child.
void Tell(const Json& j) {
  const std::string line = JsonText(j) + "\n";
  size_t done = 0;
  while (done < line.size()) {
    const ssize_t n = ::write(kReportFd, line.data() + done, line.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) ::_exit(3);
    done += static_cast<size_t>(n);
  }
}

class ChildObserver : public ProgressObserver {
 public:
  bool OnProgress(absl::string_view stage, double fraction, absl::string_view message) override {
    stage_ = std::string(stage);
    Tell({{"progress", {{"stage", stage_}, {"fraction", fraction}, {"message", message}}}});
    return true;  // the parent stops the child by killing it
  }
  const std::string& stage() const { return stage_; }

 private:
  std::string stage_ = "start";
};

// Names the volume the client knows, not this machine's path for it.
std::string AsClientSees(const absl::Status& st, const std::string& display,
                         const std::string& volume) {
  std::string message(st.message());
  if (display != volume) message = absl::StrReplaceAll(message, {{volume, display}});
  return message;
}

// The line the child sends when its volume did not open in time, made before the alarm is
// set: the handler may only write() and _exit().
std::string g_open_timeout_line;

void OnOpenTimeout(int) {
  const ssize_t n = ::write(kReportFd, g_open_timeout_line.data(), g_open_timeout_line.size());
  (void)n;
  ::_exit(1);
}

// Opens the volume once under an alarm of `seconds`, so that a header no library can finish
// reading fails the job as a bad input.
absl::Status ProbeOpen(const PipelineOptions& options, const std::string& display,
                       const std::string& volume, int64_t seconds) {
  if (seconds <= 0) return absl::OkStatus();
  g_open_timeout_line =
      JsonText({{"result",
                 {{"code", static_cast<int>(absl::StatusCode::kInvalidArgument)},
                  {"message", absl::StrCat(display, ": the volume did not open within ", seconds,
                                           " s (a damaged file whose structure loops?)")}}}}) +
      "\n";
  ::signal(SIGALRM, OnOpenTimeout);
  ::alarm(static_cast<unsigned>(seconds));
  absl::StatusOr<std::unique_ptr<VolumeSource>> source = OpenVolume(volume, options.input.open);
  ::alarm(0);
  ::signal(SIGALRM, SIG_DFL);
  if (!source.ok()) {
    return absl::Status(source.status().code(), AsClientSees(source.status(), display, volume));
  }
  return absl::OkStatus();
}

// An inspecting child opens the volume, says what it holds, and runs no stage.
int InspectChild(const PipelineOptions& options, const std::string& display,
                 const std::string& volume) {
  absl::StatusOr<std::unique_ptr<VolumeSource>> source = OpenVolume(volume, options.input.open);
  if (!source.ok()) {
    Tell({{"result",
           {{"code", static_cast<int>(source.status().code())},
            {"message", AsClientSees(source.status(), display, volume)}}}});
    return 1;
  }
  const InspectedVolume v = InspectedOf((*source)->info());
  Tell({{"result", {{"code", 0}, {"dims", v.dims}, {"dtype", v.dtype}, {"spacing", v.spacing}}}});
  return 0;
}

int ChildMain(const std::string& spec_path) {
  ChildObserver observer;
  uint64_t memory = 0;
  // `kept`: the files a failed run kept in the output folder (KeptFiles).
  auto fail = [&](absl::StatusCode code, const std::string& message,
                  const std::vector<std::string>& kept = {}) {
    Tell({{"result", {{"code", static_cast<int>(code)}, {"message", message}, {"kept", kept}}}});
    return 1;
  };
  try {
    absl::StatusOr<std::string> text = ReadFileToString(spec_path);
    if (!text.ok()) return fail(text.status().code(), std::string(text.status().message()));
    const Json spec = Json::parse(*text);
    memory = spec.value("memory_limit_bytes", uint64_t{0});
    const std::string volume = spec.at("volume_path").get<std::string>();
    const std::string display = spec.value("display_name", volume);
    const std::string out = spec.at("output_dir").get<std::string>();
    const bool data_files = spec.value("data_files", false);
    std::vector<std::string> roots = spec.value("allowed_roots", std::vector<std::string>{});
    BrickTaskSpec task;
    task.task = spec.value("task", std::string());
    task.brick_size = spec.value("brick_size", std::string());
    task.index = spec.value("brick_index", 0);
    const bool merge = task.task == "merge";  // reads the bricks, not the volume
    SandboxPaths fence;
    if (!merge) fence.read.push_back(volume);
    if (data_files) fence.read.insert(fence.read.end(), roots.begin(), roots.end());
    fence.read_write.push_back(out);
    const absl::Status fenced = RestrictFilesystem(fence);
    if (!fenced.ok())
      std::fprintf(stderr, "sheetmesh job: %s\n", std::string(fenced.message()).c_str());
    ParameterBuilder builder(ParamScope::kJob);
    absl::Status st =
        builder.AddJson(spec.at("parameters").get<std::string>(), "the job's resolved parameters");
    if (!st.ok()) return fail(st.code(), std::string(st.message()));
    absl::StatusOr<PipelineOptions> options = builder.Build();
    if (!options.ok())
      return fail(options.status().code(), std::string(options.status().message()));
    options->input.path = volume;
    VolumeLimits& limits = options->input.open.limits;
    limits.confine_named_files = true;
    limits.named_file_roots = data_files ? roots : std::vector<std::string>{};
    // Readers refuse what would not fit: half the job's address space, at once.
    if (memory > 0) limits.memory_bytes = static_cast<int64_t>(memory / 2);
    if (absl::Status opened =
            merge ? absl::OkStatus()
                  : ProbeOpen(*options, display, volume, spec.value("open_seconds", int64_t{0}));
        !opened.ok()) {
      return fail(opened.code(), std::string(opened.message()));
    }
    if (spec.value("inspect", false)) return InspectChild(*options, display, volume);
    options->output.dir = out;
    if (!task.task.empty()) {
      absl::StatusOr<std::vector<std::string>> files =
          RunBrickTask(task, *options, display, Progress(&observer, "read"));
      if (!files.ok()) {
        return fail(files.status().code(), AsClientSees(files.status(), display, volume),
                    KeptFiles(files.status()));
      }
      Tell({{"result", {{"code", 0}, {"files", *files}}}});
      return 0;
    }
    absl::StatusOr<PipelineReport> report = RunPipeline(*options, Progress(&observer, "read"));
    if (!report.ok()) {
      return fail(report.status().code(), AsClientSees(report.status(), display, volume),
                  KeptFiles(report.status()));
    }
    Tell({{"result", {{"code", 0}, {"files", report->files}}}});
    return 0;
  } catch (const std::bad_alloc&) {
    return fail(absl::StatusCode::kResourceExhausted,
                absl::StrCat("the job ran out of its memory limit",
                             memory ? absl::StrCat(" of ", Bytes(memory)) : "", " in stage ",
                             observer.stage()));
  } catch (const std::exception& e) {
    return fail(absl::StatusCode::kInternal,
                absl::StrCat("the job failed in stage ", observer.stage(), ": ", e.what()));
  }
}

// --- The parent --------------------------------------------------------------------------

// The last `bytes` of a file, for messages.
std::string Tail(const std::string& path, size_t bytes = 400) {
  absl::StatusOr<std::string> text = ReadFileToString(path);
  if (!text.ok()) return "";
  std::string s = *text;
  if (s.size() > bytes) s = "..." + s.substr(s.size() - bytes);
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

// Reads what the child wrote so far; calls `line` per complete line.
template <class Line>
void Drain(int fd, std::string* buffer, Line line) {
  char chunk[4096];
  for (;;) {
    const ssize_t n = ::read(fd, chunk, sizeof(chunk));
    if (n > 0) {
      buffer->append(chunk, static_cast<size_t>(n));
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    break;  // EAGAIN or end of file
  }
  size_t start = 0;
  for (size_t nl; (nl = buffer->find('\n', start)) != std::string::npos; start = nl + 1) {
    line(absl::string_view(*buffer).substr(start, nl - start));
  }
  buffer->erase(0, start);
}

// The status of a child that ended without a result.
absl::Status Died(const ChildExit& exit, const std::string& stage, const JobLimits& limits,
                  const std::string& log) {
  const std::string tail = Tail(log);
  if (exit.signaled && exit.code == SIGXCPU) {
    return absl::DeadlineExceededError(absl::StrCat("the job used up its CPU limit of ",
                                                    limits.cpu_seconds, " s in stage ", stage));
  }
  if (tail.find("bad_alloc") != std::string::npos) {
    return absl::ResourceExhaustedError(absl::StrCat("the job ran out of its memory limit of ",
                                                     Bytes(limits.memory_bytes), " in stage ",
                                                     stage));
  }
  std::string what = absl::StrCat("the job was ", exit.signaled ? "" : "ended: ", exit.ToString(),
                                  " in stage ", stage);
  if (exit.signaled && exit.code == SIGBUS) {
    absl::StrAppend(&what, " (a file it read shrank or changed while it read it)");
  }
  if (exit.signaled && exit.code != SIGBUS && (stage == "start" || stage == "read")) {
    // Before any stage of ours ran on it: a reader library crashed on the input.
    absl::StrAppend(&what,
                    " (while reading the volume: a library crashed on it; is the file "
                    "damaged?)");
  }
  if (!tail.empty()) absl::StrAppend(&what, "; its last output: ", tail);
  return absl::InternalError(what);
}

}  // namespace

InspectedVolume InspectedOf(const VolumeInfo& info) {
  const Vec3& s = info.placement.spacing;
  return {{info.dims.nx, info.dims.ny, info.dims.nz},
          std::string(DTypeName(info.dtype)),
          {s.x, s.y, s.z}};
}

uint64_t DefaultJobMemory() {
  const uint64_t bytes = PhysicalMemoryBytes(0);
  return bytes > 0 ? bytes / 4 * 3 : uint64_t{8} << 30;
}

absl::StatusOr<std::string> SelfPath() {
  std::error_code ec;
  const std::filesystem::path p = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return absl::InternalError(absl::StrCat("/proc/self/exe: ", ec.message()));
  return p.string();
}

int RunJobChildIfAsked(int argc, char** argv) {
  if (argc < 2 || std::strcmp(argv[1], kChildFlag) != 0) return -1;
  if (argc != 3) return 2;
  ::signal(SIGPIPE, SIG_DFL);
  return ChildMain(argv[2]);
}

namespace {

// Runs the child for `spec` and returns its result line (code 0) or the status it ended with.
absl::StatusOr<Json> RunChild(const std::string& self, const JobSpec& spec, const JobLimits& limits,
                              const JobProgressFn& progress) {
  const std::string spec_path = spec.output_dir + ".spec.json";
  const std::string log = spec.output_dir + ".log";
  struct Cleanup {
    std::vector<std::string> files;
    ~Cleanup() {
      for (const std::string& f : files) ::unlink(f.c_str());
    }
  } cleanup{{spec_path, log}};
  const Json j = {{"volume_path", spec.volume_path},
                  {"display_name", spec.display_name},
                  {"output_dir", spec.output_dir},
                  {"parameters", spec.parameters},
                  {"allowed_roots", spec.allowed_roots},
                  {"data_files", spec.data_files},
                  {"inspect", spec.inspect},
                  {"task", spec.brick.task},
                  {"brick_size", spec.brick.brick_size},
                  {"brick_index", spec.brick.index},
                  {"memory_limit_bytes", limits.memory_bytes},
                  {"open_seconds", absl::ToInt64Seconds(limits.open)}};
  SM_RETURN_IF_ERROR(WriteFileAtomically(spec_path, JsonText(j)));
  SubprocessOptions o;
  o.argv = {self, kChildFlag, spec_path};
  o.output_path = log;
  o.memory_limit_bytes = limits.memory_bytes;
  o.cpu_limit_seconds = limits.cpu_seconds;
  o.report_pipe = true;
  // The server's environment may hold secrets (PGPASSWORD, tokens): a job sees none of it.
  o.env = {{"TMPDIR", spec.output_dir}, {"LC_ALL", "C"}};
  o.clean_env = true;
  o.keep_env = {"PATH", "GLIBC_TUNABLES", "SHEETMESH_NO_HUGE_PAGES"};
  SM_ASSIGN_OR_RETURN(Subprocess child, Subprocess::Start(o));
  ::fcntl(child.report_fd(), F_SETFL, O_NONBLOCK);
  const auto deadline = std::chrono::steady_clock::now() + absl::ToChronoMilliseconds(limits.wall);
  std::string buffer, stage = "start";
  std::optional<Json> result;
  bool stop = false;
  double fraction = 0;
  auto last_report = std::chrono::steady_clock::now();
  auto on_line = [&](absl::string_view line) {
    const Json m = Json::parse(line.begin(), line.end(), nullptr, /*allow_exceptions=*/false);
    if (m.is_discarded()) return;
    if (m.contains("progress")) {
      const Json& p = m["progress"];
      stage = p.value("stage", stage);
      fraction = p.value("fraction", 0.0);
      last_report = std::chrono::steady_clock::now();
      if (!stop && !progress(stage, fraction, p.value("message", ""))) stop = true;
    } else if (m.contains("result")) {
      result = m["result"];
    }
  };
  std::optional<ChildExit> exit;
  for (;;) {
    struct pollfd pfd = {child.report_fd(), POLLIN, 0};
    ::poll(&pfd, 1, 100);
    Drain(child.report_fd(), &buffer, on_line);
    if ((exit = child.Poll())) {
      Drain(child.report_fd(), &buffer, on_line);
      break;
    }
    // A stage that reports rarely still lets the host say stop (a cancel, a lost lease):
    // the last progress again, a few times a second.
    if (const auto now = std::chrono::steady_clock::now();
        !stop && now - last_report > std::chrono::milliseconds(250)) {
      last_report = now;
      if (!progress(stage, fraction, "")) stop = true;
    }
    if (stop) {
      child.Kill();
      child.Wait();
      return absl::CancelledError(absl::StrCat("the job was stopped in stage ", stage));
    }
    if (std::chrono::steady_clock::now() > deadline) {
      child.Kill();
      child.Wait();
      return absl::DeadlineExceededError(absl::StrCat("the job ran past its time limit of ",
                                                      absl::FormatDuration(limits.wall),
                                                      " in stage ", stage));
    }
  }
  if (!result) return Died(*exit, stage, limits, log);
  const int code = result->value("code", static_cast<int>(absl::StatusCode::kInternal));
  if (code != 0) {
    return WithKeptFiles(
        absl::Status(static_cast<absl::StatusCode>(code), result->value("message", "")),
        result->value("kept", std::vector<std::string>{}));
  }
  return *result;
}

}  // namespace

absl::StatusOr<std::vector<std::string>> RunJobInChild(const std::string& self, const JobSpec& spec,
                                                       const JobLimits& limits,
                                                       const JobProgressFn& progress) {
  JobSpec job = spec;
  job.inspect = false;
  SM_ASSIGN_OR_RETURN(const Json result, RunChild(self, job, limits, progress));
  return result.value("files", std::vector<std::string>{});
}

absl::StatusOr<InspectedVolume> InspectVolumeInChild(const std::string& self, const JobSpec& spec,
                                                     const JobLimits& limits) {
  JobSpec inspect = spec;
  inspect.inspect = true;
  SM_ASSIGN_OR_RETURN(const Json result, RunChild(self, inspect, limits,
                                                  [](const std::string&, double,
                                                     const std::string&) { return true; }));
  InspectedVolume v;
  try {
    v.dims = result.at("dims").get<std::array<int64_t, 3>>();
    v.dtype = result.at("dtype").get<std::string>();
    v.spacing = result.at("spacing").get<std::array<double, 3>>();
  } catch (const Json::exception& e) {
    return absl::InternalError(absl::StrCat("the inspecting child answered wrongly: ", e.what()));
  }
  return v;
}

}  // namespace sheetmesh::runtime
