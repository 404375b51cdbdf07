// sheetmesh-worker: leases jobs from sheetmesh-server replicas over gRPC and runs them on
// this machine — inputs from the servers' blob store (or shared storage under
// --allowed_root), artifacts back to it. SIGTERM or SIGINT drain: running jobs may finish
// for --drain_seconds, then they go back to the queue.
//   sheetmesh-worker --server=HOST:PORT --scratch_dir=DIR [--token_file=F] [--workers=N]
//                    [--tls [--tls_root_cert=ca.pem]] [--allowed_root=/lab/scans,...]
#include <signal.h>
#include <unistd.h>

#include <iostream>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "absl/time/clock.h"
#include "common/file_util.h"
#include "common/flags_help.h"
#include "worker/remote/remote_job_host.h"
#include "worker/runtime/job_limit_flags.h"
#include "worker/runtime/job_process.h"
#include "worker/runtime/worker_pool.h"

ABSL_FLAG(std::string, server, "127.0.0.1:50051", "a sheetmesh-server, host:port");
ABSL_FLAG(std::string, token_file, "",
          "file with the server's worker token (--worker_token_file there)");
ABSL_FLAG(bool, tls, false, "TLS to the server (system roots, or --tls_root_cert)");
ABSL_FLAG(std::string, tls_root_cert, "", "PEM roots to trust for the server");
ABSL_FLAG(std::string, scratch_dir, "",
          "where inputs and outputs of running jobs go (required); the last uploaded volume "
          "stays in DIR/cache for the next brick of its job");
ABSL_FLAG(std::string, allowed_root, "",
          "shared storage jobs may name by path, comma-separated (none: only uploaded volumes)");
ABSL_FLAG(int, workers, 1, "jobs run at once");
ABSL_FLAG(std::string, name, "", "this worker's name in leases (default: host and pid)");
ABSL_FLAG(int, drain_seconds, absl::ToInt64Seconds(sheetmesh::runtime::kDefaultDrain),
          "on SIGTERM, how long running jobs may finish");
// --isolate_jobs and the job limits: worker/runtime/job_limit_flags.cc.
ABSL_FLAG(int, renew_seconds,
          absl::ToInt64Seconds(sheetmesh::runtime::WorkerPoolOptions().renew_interval),
          "lease renewal period (below a third of the server's lease)");

int main(int argc, char** argv) {
  if (const int code = sheetmesh::runtime::RunJobChildIfAsked(argc, argv); code >= 0) return code;
  absl::SetProgramUsageMessage("sheetmesh-worker --server=HOST:PORT --scratch_dir=DIR [flags]");
  if (sheetmesh::WantsVersion(argc, argv)) {
    sheetmesh::PrintVersion("sheetmesh-worker", std::cout);
    return 0;
  }
  if (sheetmesh::WantsHelp(argc, argv)) {
    std::cout << "sheetmesh-worker --server=HOST:PORT --scratch_dir=DIR [flags]\n\n";
    sheetmesh::PrintFlagsOf("worker/remote/main.cc", std::cout);
    sheetmesh::PrintFlagsOf(sheetmesh::runtime::kJobLimitFlagsFile, std::cout);
    return 0;
  }
  sheetmesh::ParseFlagsOrExit(argc, argv, "sheetmesh-worker");
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  sheetmesh::remote::RemoteJobHostOptions ho;
  ho.server.address = absl::GetFlag(FLAGS_server);
  ho.server.tls = absl::GetFlag(FLAGS_tls) || !absl::GetFlag(FLAGS_tls_root_cert).empty();
  ho.server.tls_root_cert = absl::GetFlag(FLAGS_tls_root_cert);
  if (const std::string f = absl::GetFlag(FLAGS_token_file); !f.empty()) {
    absl::StatusOr<std::string> token = sheetmesh::ReadFileToString(f);
    if (!token.ok()) {
      std::cerr << "sheetmesh-worker: --token_file: " << token.status() << "\n";
      return 2;
    }
    ho.server.auth_token = std::string(absl::StripAsciiWhitespace(*token));
  }
  ho.scratch_dir = absl::GetFlag(FLAGS_scratch_dir);
  for (absl::string_view r :
       absl::StrSplit(absl::GetFlag(FLAGS_allowed_root), ',', absl::SkipEmpty())) {
    ho.allowed_roots.emplace_back(r);
  }
  if (absl::GetFlag(FLAGS_workers) < 1) {
    std::cerr << "sheetmesh-worker: --workers=" << absl::GetFlag(FLAGS_workers)
              << ": must be at least 1\n";
    return 2;
  }
  auto host = sheetmesh::remote::RemoteJobHost::Connect(ho);
  if (!host.ok()) {
    std::cerr << "sheetmesh-worker: " << host.status() << "\n";
    if (const std::string hint = sheetmesh::client::ConnectionHint(host.status(), ho.server);
        !hint.empty()) {
      std::cerr << hint << "\n";
    }
    return 2;
  }
  sheetmesh::runtime::WorkerPoolOptions wo;
  wo.workers = absl::GetFlag(FLAGS_workers);
  wo.name = absl::GetFlag(FLAGS_name).empty() ? sheetmesh::runtime::UniqueWorkerName("remote")
                                              : absl::GetFlag(FLAGS_name);
  wo.run.scratch_dir = ho.scratch_dir + "/jobs";
  wo.run.isolate = sheetmesh::runtime::IsolateJobsFromFlags();
  wo.run.limits = sheetmesh::runtime::JobLimitsFromFlags();
  wo.renew_interval = absl::Seconds(std::max(1, absl::GetFlag(FLAGS_renew_seconds)));
  if (absl::Status st = sheetmesh::MakeDirs(wo.run.scratch_dir); !st.ok()) {
    std::cerr << "sheetmesh-worker: " << st << "\n";
    return 2;
  }
  sheetmesh::runtime::WorkerPool pool(host->get(), wo);
  pool.Start();
  std::cerr << "sheetmesh-worker " << wo.name << ": " << wo.workers << " worker(s) on "
            << ho.server.address << std::endl;
  int sig = 0;
  sigwait(&signals, &sig);
  std::cerr << "sheetmesh-worker: " << (sig == SIGTERM ? "SIGTERM" : "SIGINT")
            << ", draining for up to " << absl::GetFlag(FLAGS_drain_seconds) << " s" << std::endl;
  (*host)->Stop();
  pool.Drain(absl::Seconds(absl::GetFlag(FLAGS_drain_seconds)));
  return 0;
}
