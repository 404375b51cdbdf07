// sheetmesh: the command-line client of the sheetmesh service.
//   sheetmesh mesh VOLUME -o DIR [--reference] [any pipeline parameter: --r R --extract ...]
//   sheetmesh upload FILE
//   sheetmesh jobs list|get|watch|cancel|delete [JOB]
//   sheetmesh artifacts get JOB [-o DIR] [--name FILE]
//   sheetmesh health
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <initializer_list>
#include <iostream>
#include <optional>
#include <random>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/ascii.h"
#include "absl/strings/cord.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "client/client.h"
#include "client/parameter_flags.h"
#include "common/exit_codes.h"
#include "common/file_util.h"
#include "common/flags_help.h"
#include "common/json_parse.h"
#include "common/progress_line.h"
#include "common/status_macros.h"
#include "google/protobuf/util/json_util.h"
#include "sheetmesh/v1/job_states.h"

ABSL_FLAG(std::string, server, "127.0.0.1:50051", "the server's host:port");
ABSL_FLAG(std::string, token, "", "bearer token (or $SHEETMESH_TOKEN)");
ABSL_FLAG(bool, tls, false, "use TLS (system roots)");
ABSL_FLAG(std::string, tls_root_cert, "", "PEM root certificate for TLS");
ABSL_FLAG(std::string, o, "", "output folder");
ABSL_FLAG(bool, reference, false,
          "mesh: name the volume by its path on the server instead of uploading it");
ABSL_FLAG(std::string, config, "",
          "mesh: a JSON file of pipeline parameters (as for sheetmesh-pipeline); parameter "
          "flags (--r=5, --extract, --separate_r=6, --labels=255, --dims=64x64x64, ...: "
          "sheetmesh-pipeline params lists them) override it");
ABSL_FLAG(bool, no_cache, false, "mesh: run even when identical work is done");
ABSL_FLAG(std::string, bricks, "",
          "mesh: run the job as bricks of this size (auto, 512, 512x512x256), spread over the "
          "server's workers; the result is the same");
ABSL_FLAG(std::string, state, "", "jobs list: only jobs in this state (QUEUED, RUNNING, ...)");
ABSL_FLAG(int, page_size, 50, "jobs list: jobs per page");
ABSL_FLAG(bool, all_pages, false, "jobs list: follow every page");
ABSL_FLAG(std::string, name, "", "artifacts get: only this file");
ABSL_FLAG(bool, json, false, "print jobs as JSON");

namespace sheetmesh::client {
namespace {

// A number of the report at the path of keys given, if it is there.
std::optional<double> NumberAt(const nlohmann::json& report,
                               std::initializer_list<const char*> path) {
  const nlohmann::json* at = &report;
  for (const char* key : path) {
    if (!at->is_object()) return std::nullopt;
    const auto it = at->find(key);
    if (it == at->end()) return std::nullopt;
    at = &*it;
  }
  if (!at->is_number()) return std::nullopt;
  return at->get<double>();
}

// The job's figures from its report, as the offline CLI's summary gives them: the surface's
// triangles, pieces and similarity, the volume mesh's tetrahedra and angles.
void PrintFigures(const nlohmann::json& report) {
  if (const std::optional<double> triangles = NumberAt(report, {"surface", "triangles"})) {
    std::cout << absl::StrFormat("surface   %.0f triangles", *triangles);
    const auto pieces = report.find("pieces");
    if (pieces != report.end() && pieces->is_array()) {
      std::cout << " in " << pieces->size() << (pieces->size() == 1 ? " piece" : " pieces");
    }
    if (const std::optional<double> s = NumberAt(report, {"similarity", "similarity"})) {
      std::cout << absl::StrFormat(", similarity %.4f", *s);
    }
    std::cout << "\n";
  }
  if (const std::optional<double> tets = NumberAt(report, {"volume_mesh", "tetrahedra"})) {
    std::cout << absl::StrFormat("volume    %.0f tetrahedra", *tets);
    const auto min = NumberAt(report, {"volume_mesh", "quality", "min_dihedral_degrees", "min"});
    const auto mean = NumberAt(report, {"volume_mesh", "quality", "min_dihedral_degrees", "mean"});
    if (min && mean) std::cout << absl::StrFormat(", min dihedral %.2f° (mean %.2f°)", *min, *mean);
    std::cout << "\n";
  }
}

// The figures and the warnings a job's report carries, as the offline CLI prints them: a
// volume mesh whose smallest dihedral angle is under tet.min_dihedral (where, and why). A
// report that is missing or does not parse says nothing here (the files are the user's to
// read).
void PrintWarnings(const std::string& dir) {
  absl::StatusOr<std::string> text = ReadFileToString(dir + "/report.json");
  if (!text.ok()) return;
  absl::StatusOr<nlohmann::json> report = ParseJson(*text, "report.json");
  if (!report.ok() || !report->is_object()) return;
  PrintFigures(*report);
  // The report's warnings: a surface under the grid floor, a volume mesh under its aim.
  for (const auto& [section, key] :
       {std::pair<const char*, const char*>{"similarity", "floor_warning"},
        {"volume_mesh", "angle_warning"}}) {
    const auto s = report->find(section);
    if (s == report->end() || !s->is_object()) continue;
    const auto w = s->find(key);
    if (w != s->end() && w->is_object() && w->contains("text") && (*w)["text"].is_string()) {
      std::cout << "warning   " << (*w)["text"].get<std::string>() << "\n";
    }
  }
}

constexpr char kUsage[] =
    "sheetmesh COMMAND [ARGS] [--server=host:port]\n\n"
    "  mesh VOLUME -o DIR        upload (or --reference) a volume, run a job, download its files;\n"
    "                            every pipeline parameter is a flag: --r=5 --extract\n"
    "                            --volume_mesh --labels=255 (sheetmesh-pipeline params)\n"
    "  upload FILE               upload a file, print its digest\n"
    "  jobs list|get|watch|cancel|delete [JOB]\n"
    "  artifacts get JOB -o DIR  download a job's files (--name FILE for one)\n"
    "  health                    the server's health\n";

// The payload that marks a status as the end of a job (not a refused call).
constexpr char kJobFailed[] = "sheetmesh/job-failed";
// The payload that marks a status as about the user's own files on this machine.
constexpr char kUserInput[] = "sheetmesh/user-input";

// 2 for bad input the user can mend: refused parameters, a volume of theirs that is missing
// here, and a job that failed on its volume (bad, cut, too big for the server's budget,
// naming a file it may not); 1 for the rest (the server, the network, a job or blob the
// server does not have).
int ExitCodeOf(const absl::Status& st) {
  return sheetmesh::ExitCodeOf(
      st, st.GetPayload(kJobFailed).has_value() || st.GetPayload(kUserInput).has_value());
}

std::string NewRequestId() {
  std::random_device rd;
  std::mt19937_64 rng((uint64_t(rd()) << 32) ^ rd() ^ absl::GetCurrentTimeNanos());
  return absl::StrFormat("%016x%016x", rng(), rng());
}

std::string StateName(v1::JobState s) { return v1::JobState_Name(s); }

// "stage 3/6 surface 42%", or "starting" for a job leased that has not begun its first stage.
std::string StageText(const v1::JobProgress& p) {
  return ProgressLine::StageText(p.stage_index(), p.stage_count(), p.stage(), p.fraction(),
                                 absl::InfiniteDuration());
}

void PrintJob(const v1::Job& j) {
  if (absl::GetFlag(FLAGS_json)) {
    std::string out;
    google::protobuf::util::JsonPrintOptions o;
    o.add_whitespace = true;
    (void)google::protobuf::util::MessageToJsonString(j, &out, o);
    std::cout << out << "\n";
    return;
  }
  std::cout << absl::StrFormat("%s  %-9s", j.name(), StateName(j.state()));
  if (j.state() == v1::RUNNING) std::cout << "  " << StageText(j.progress());
  if (!j.cached_from().empty()) std::cout << "  (cached from " << j.cached_from() << ")";
  if (j.has_error() && j.error().code() != 0) std::cout << "  error: " << j.error().message();
  std::cout << "\n";
}

// Progress as a bar on a terminal, as lines otherwise; each other state on a line of its own.
class Reporter {
 public:
  Reporter() : line_(std::cout, ::isatty(1)) {}
  void Update(const v1::WatchJobResponse& m) {
    const v1::Job& j = m.job();
    if (j.state() == v1::RUNNING) {
      const v1::JobProgress& p = j.progress();
      line_.Show(StateName(j.state()), p.stage_index(), p.stage_count(), p.stage(), p.fraction());
      state_.clear();
      return;
    }
    if (StateName(j.state()) == state_) return;
    state_ = StateName(j.state());
    line_.Finish(state_);
  }
  void Done() { line_.Finish(""); }

 private:
  ProgressLine line_;
  std::string state_;
};

// A job's artifacts into `dir` (only the one named `only`, unless empty): every output of a
// job that SUCCEEDED, what a FAILED job's run kept. A job that has not ended, or ended with
// none, is kFailedPrecondition.
absl::Status DownloadAll(SheetmeshClient& c, const v1::Job& job, const std::string& dir,
                         const std::string& only) {
  if (job.artifacts().empty()) {
    const bool ended = v1::IsTerminal(job.state());
    return absl::FailedPreconditionError(
        ended ? absl::StrCat(job.name(), " is ", StateName(job.state()), " and kept no file")
              : absl::StrCat(job.name(), " is ", StateName(job.state()),
                             "; its files come when it ends"));
  }
  if (!only.empty() && std::none_of(job.artifacts().begin(), job.artifacts().end(),
                                    [&](const v1::Artifact& a) { return a.name() == only; })) {
    std::string names;
    for (const v1::Artifact& a : job.artifacts())
      absl::StrAppend(&names, names.empty() ? "" : ", ", a.name());
    return absl::NotFoundError(
        absl::StrCat(job.name(), " has no file '", only, "' (it has: ", names, ")"));
  }
  SM_RETURN_IF_ERROR(MakeDirs(dir));
  for (const v1::Artifact& a : job.artifacts()) {
    if (!only.empty() && a.name() != only) continue;
    const std::string path =
        (std::filesystem::path(dir) / std::filesystem::path(a.name()).filename()).string();
    SM_RETURN_IF_ERROR(c.Download(a.digest(), path));
    std::cout << absl::StrFormat("  %-40s %12d bytes\n", path, a.digest().size_bytes());
  }
  return absl::OkStatus();
}

absl::Status Mesh(SheetmeshClient& c, const std::vector<std::string>& args,
                  const v1::PipelineParameters& parameters, const v1::VolumeFormat& format) {
  if (args.size() != 1) return absl::InvalidArgumentError("usage: sheetmesh mesh VOLUME -o DIR");
  const std::string out = absl::GetFlag(FLAGS_o);
  if (out.empty()) return absl::InvalidArgumentError("mesh needs -o DIR");
  v1::CreateJobRequest req;
  req.set_request_id(NewRequestId());
  req.set_no_cache(absl::GetFlag(FLAGS_no_cache));
  req.set_bricks(absl::GetFlag(FLAGS_bricks));
  v1::JobInput& in = *req.mutable_input();
  in.set_file_name(std::filesystem::path(args[0]).filename().string());
  // The user's own volume, a folder of slices or a file.h5:/dataset: a missing one is theirs
  // to mend (exit 2), unlike a job the server does not have.
  std::error_code ec;
  const std::string local = args[0].substr(0, args[0].rfind(":/"));
  if (!absl::GetFlag(FLAGS_reference) && !std::filesystem::exists(local, ec)) {
    absl::Status missing = absl::NotFoundError(absl::StrCat(local, ": no such file or folder"));
    missing.SetPayload(kUserInput, absl::Cord("1"));
    return missing;
  }
  if (absl::GetFlag(FLAGS_reference)) {
    in.set_volume_path(std::filesystem::absolute(args[0]).string());
  } else if (std::filesystem::is_directory(args[0]) ||
             absl::AsciiStrToLower(std::filesystem::path(args[0]).extension().string()) ==
                 ".nhdr") {
    // A folder of slices, or a detached header and its data file: one volume of files,
    // of which only those the server lacks travel.
    in.set_file_name(std::filesystem::path(args[0]).lexically_normal().filename().string());
    if (in.file_name().empty()) {
      in.set_file_name(std::filesystem::absolute(args[0]).parent_path().filename().string());
    }
    SM_ASSIGN_OR_RETURN(VolumeOnDisk files, VolumeFilesOf(args[0]));
    const bool tty = ::isatty(1);
    SM_ASSIGN_OR_RETURN(
        VolumeUpload up, c.UploadVolumeFiles(files.files, [tty](int64_t sent, int64_t total) {
          if (tty)
            std::cout << absl::StrFormat("\rupload %5.1f%% of %d bytes",
                                         100.0 * sent / std::max<int64_t>(1, total), total)
                      << std::flush;
        }));
    if (tty) std::cout << "\n";
    std::cout << absl::StrFormat(
        "volume of %d files (%d bytes): sent %d (%d bytes), %d stored already\n",
        up.files.files_size(), up.total_bytes, up.files_sent, up.bytes_sent,
        up.files.files_size() - up.files_sent);
    *in.mutable_volume_files() = std::move(up.files);
    in.mutable_volume_files()->set_main(files.main);
  } else {
    const bool tty = ::isatty(1);
    SM_ASSIGN_OR_RETURN(v1::Digest d, c.Upload(args[0], [tty](int64_t sent, int64_t total) {
      if (tty)
        std::cout << absl::StrFormat("\rupload %5.1f%% of %d bytes",
                                     100.0 * sent / std::max<int64_t>(1, total), total)
                  << std::flush;
    }));
    if (tty) std::cout << "\n";
    std::cout << "volume " << d.hash() << " (" << d.size_bytes() << " bytes)\n";
    *in.mutable_volume_digest() = d;
  }
  v1::PipelineParameters& p = *req.mutable_parameters();
  p = parameters;
  *in.mutable_format() = format;
  if (!absl::GetFlag(FLAGS_config).empty()) {
    SM_ASSIGN_OR_RETURN(std::string cfg, ReadFileToString(absl::GetFlag(FLAGS_config)));
    p.set_config_json(cfg);
  }
  SM_ASSIGN_OR_RETURN(v1::Job job, c.CreateJob(req));
  std::cout << "job " << job.name()
            << (job.cached_from().empty()
                    ? ""
                    : " (identical work done before: " + job.cached_from() + ")")
            << "\n";
  Reporter reporter;
  SM_ASSIGN_OR_RETURN(v1::Job done, c.Watch(job.name(), [&](const v1::WatchJobResponse& m) {
    reporter.Update(m);
  }));
  reporter.Done();
  if (done.state() != v1::SUCCEEDED) {
    absl::Status failed(
        static_cast<absl::StatusCode>(done.error().code() ? done.error().code() : 2),
        absl::StrCat(done.name(), " ", StateName(done.state()), ": ", done.error().message()));
    failed.SetPayload(kJobFailed, absl::Cord(done.name()));
    if (done.artifacts_size() > 0) {
      std::cout << "downloading the " << done.artifacts_size() << " files it kept to " << out
                << "\n";
      SM_RETURN_IF_ERROR(DownloadAll(c, done, out, ""));
    }
    return failed;
  }
  std::cout << "downloading " << done.artifacts_size() << " files to " << out << "\n";
  SM_RETURN_IF_ERROR(DownloadAll(c, done, out, ""));
  PrintWarnings(out);
  std::cout << "results in " << std::filesystem::absolute(out).string() << "\n";
  return absl::OkStatus();
}

absl::Status Jobs(SheetmeshClient& c, const std::vector<std::string>& args) {
  if (args.empty())
    return absl::InvalidArgumentError("usage: sheetmesh jobs list|get|watch|cancel|delete [JOB]");
  const std::string& verb = args[0];
  if (verb == "list") {
    v1::ListJobsRequest req;
    req.set_page_size(absl::GetFlag(FLAGS_page_size));
    if (!absl::GetFlag(FLAGS_state).empty()) {
      v1::JobState s;
      if (!v1::JobState_Parse(absl::GetFlag(FLAGS_state), &s)) {
        return absl::InvalidArgumentError(
            absl::StrCat("--state=", absl::GetFlag(FLAGS_state), " is not a job state"));
      }
      req.set_state(s);
    }
    do {
      SM_ASSIGN_OR_RETURN(v1::ListJobsResponse resp, c.ListJobs(req));
      for (const v1::Job& j : resp.jobs()) PrintJob(j);
      req.set_page_token(resp.next_page_token());
    } while (absl::GetFlag(FLAGS_all_pages) && !req.page_token().empty());
    return absl::OkStatus();
  }
  if (args.size() != 2)
    return absl::InvalidArgumentError(absl::StrCat("usage: sheetmesh jobs ", verb, " JOB"));
  if (verb == "get") {
    SM_ASSIGN_OR_RETURN(v1::Job j, c.GetJob(args[1]));
    PrintJob(j);
  } else if (verb == "watch") {
    Reporter reporter;
    SM_ASSIGN_OR_RETURN(
        v1::Job j, c.Watch(args[1], [&](const v1::WatchJobResponse& m) { reporter.Update(m); }));
    reporter.Done();
    PrintJob(j);
  } else if (verb == "cancel") {
    SM_ASSIGN_OR_RETURN(v1::Job j, c.CancelJob(args[1]));
    PrintJob(j);
  } else if (verb == "delete") {
    SM_RETURN_IF_ERROR(c.DeleteJob(args[1]));
    std::cout << "deleted " << JobName(args[1]) << "\n";
  } else {
    return absl::InvalidArgumentError(absl::StrCat("jobs ", verb, " is not known"));
  }
  return absl::OkStatus();
}

int Main(int argc, char** argv) {
  absl::SetProgramUsageMessage(kUsage);
  if (WantsVersion(argc, argv)) {
    PrintVersion("sheetmesh", std::cout);
    return 0;
  }
  if (WantsHelp(argc, argv)) {
    std::cout << kUsage << "\nflags:\n";
    PrintFlagsOf("client/main.cc", std::cout);
    std::cout << "  and every pipeline parameter as a flag of its name (mesh only)\n";
    return 0;
  }
  v1::PipelineParameters parameters;
  v1::VolumeFormat format;
  absl::StatusOr<std::vector<char*>> unparsed =
      TakeParameterFlags(argc, argv, &parameters, &format);
  if (!unparsed.ok()) {
    std::cerr << "sheetmesh: " << unparsed.status().message() << "\n";
    return 2;
  }
  std::vector<char*> rest = sheetmesh::ParseFlagsOrExit(static_cast<int>(unparsed->size()),
                                                        unparsed->data(), "sheetmesh");
  if (rest.size() < 2) {
    std::cerr << kUsage;
    return 2;
  }
  ClientOptions o;
  o.address = absl::GetFlag(FLAGS_server);
  o.auth_token = absl::GetFlag(FLAGS_token);
  if (o.auth_token.empty() && getenv("SHEETMESH_TOKEN") != nullptr)
    o.auth_token = getenv("SHEETMESH_TOKEN");
  o.tls = absl::GetFlag(FLAGS_tls);
  o.tls_root_cert = absl::GetFlag(FLAGS_tls_root_cert);
  const std::string command = rest[1];
  const std::vector<std::string> args(rest.begin() + 2, rest.end());
  absl::Status st;
  auto client = SheetmeshClient::Connect(o);
  if (!client.ok()) {
    st = client.status();
  } else if (command == "mesh") {
    st = Mesh(**client, args, parameters, format);
  } else if (command == "upload") {
    if (args.size() != 1) {
      st = absl::InvalidArgumentError("usage: sheetmesh upload FILE");
    } else {
      auto d = (*client)->Upload(args[0]);
      if (d.ok()) std::cout << d->hash() << "/" << d->size_bytes() << "\n";
      st = d.status();
    }
  } else if (command == "jobs") {
    st = Jobs(**client, args);
  } else if (command == "artifacts") {
    if (args.size() != 2 || args[0] != "get") {
      st = absl::InvalidArgumentError("usage: sheetmesh artifacts get JOB -o DIR [--name FILE]");
    } else {
      auto job = (*client)->GetJob(args[1]);
      st = job.ok() ? DownloadAll(**client, *job,
                                  absl::GetFlag(FLAGS_o).empty() ? "." : absl::GetFlag(FLAGS_o),
                                  absl::GetFlag(FLAGS_name))
                    : job.status();
    }
  } else if (command == "health") {
    auto h = (*client)->Health();
    if (h.ok()) std::cout << *h << "\n";
    st = h.ok() && *h != "SERVING" ? absl::UnavailableError(*h) : h.status();
  } else {
    std::cerr << "unknown command '" << command << "'\n\n" << kUsage;
    return 2;
  }
  if (!st.ok()) {
    std::cerr << "sheetmesh " << command << ": " << absl::StatusCodeToString(st.code()) << ": "
              << st.message() << "\n";
    if (const std::string hint = ConnectionHint(st, o); !hint.empty()) std::cerr << hint << "\n";
    return ExitCodeOf(st);
  }
  return 0;
}

}  // namespace
}  // namespace sheetmesh::client

int main(int argc, char** argv) { return sheetmesh::client::Main(argc, argv); }
