// sheetmesh-server: the service on the embedded default — one process, one data folder.
//   sheetmesh-server --data_dir=DIR [--address=127.0.0.1:50051] [--workers=N]
//                    [--allowed_root=/data/scans,...] [--auth_token=...] [--tls_cert/--tls_key]
// SIGTERM or SIGINT drain the workers (up to --drain_seconds) and stop.
#include <signal.h>
#include <sys/resource.h>

#include <iostream>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/time/time.h"
#include "common/file_util.h"
#include "common/flags_help.h"
#include "common/huge_pages.h"
#include "server/server.h"
#include "worker/runtime/job_limit_flags.h"
#include "worker/runtime/job_process.h"
#include "worker/runtime/worker_pool.h"

namespace {
// The flags' defaults are the options' own (server.h): written once.
const sheetmesh::server::ServerOptions& Defaults() {
  static const sheetmesh::server::ServerOptions defaults;
  return defaults;
}
}  // namespace

ABSL_FLAG(std::string, address, Defaults().address,
          "host:port to listen on (port 0: any free port)");
ABSL_FLAG(std::string, data_dir, "", "folder of the job store, blobs and scratch (required)");
ABSL_FLAG(
    std::string, postgres, "",
    "libpq connection string (\"host=db dbname=sheetmesh user=sheetmesh\" or postgresql://...): "
    "jobs in PostgreSQL, shared by every server over it and one blob folder, instead of "
    "DATA_DIR/jobs.db");
ABSL_FLAG(std::string, scratch_dir, "",
          "the workers' scratch, emptied at start (default DATA_DIR/scratch; each server its own "
          "when several share a data folder)");
ABSL_FLAG(bool, local_workers, Defaults().local_workers,
          "run jobs in this process's workers (false: only remote sheetmesh-workers run them)");
ABSL_FLAG(int, workers, Defaults().workers, "in-process workers (0: the number of cores)");
ABSL_FLAG(std::string, allowed_root, "",
          "comma-separated folders whose volumes jobs may name by path");
ABSL_FLAG(std::string, auth_token, "",
          "bearer token every call must carry, of the tenant 'default' ('' = none)");
ABSL_FLAG(std::string, auth_token_file, "",
          "tokens and their tenants, one 'TOKEN [TENANT]' per line ('#' comments); a tenant "
          "sees only its own jobs, uploads and artifacts");
ABSL_FLAG(std::string, worker_token_file, "",
          "file with the token remote workers (sheetmesh-worker) present; without it a server "
          "with tokens takes no remote workers, an open one any");
ABSL_FLAG(std::string, tls_cert, "", "PEM certificate chain (with --tls_key: TLS)");
ABSL_FLAG(std::string, tls_key, "", "PEM private key");
ABSL_FLAG(int64_t, max_blob_bytes, Defaults().limits.max_blob_bytes,
          "largest upload accepted, bytes");
ABSL_FLAG(int64_t, max_queued_jobs, Defaults().limits.max_queued_jobs,
          "jobs and brick tasks the queue may hold");
ABSL_FLAG(int, max_brick_tasks, Defaults().limits.max_brick_tasks,
          "bricks one job may split into (a plan of more fails the job, naming this)");
ABSL_FLAG(int64_t, max_unfinished_upload_mb,
          Defaults().limits.max_unfinished_upload_bytes_per_tenant >> 20,
          "bytes one tenant may hold in unfinished uploads, MiB");
ABSL_FLAG(int, max_upload_streams, Defaults().limits.max_upload_streams,
          "open upload (Write) streams, in all");
ABSL_FLAG(int, max_upload_streams_per_client, Defaults().limits.max_upload_streams_per_client,
          "open upload streams of one client (its tenant; on an open server, its address)");
ABSL_FLAG(int, max_watch_streams, Defaults().limits.max_watch_streams,
          "open WatchJob streams, in all");
ABSL_FLAG(int, max_watch_streams_per_client, Defaults().limits.max_watch_streams_per_client,
          "open WatchJob streams of one client");
ABSL_FLAG(int, upload_idle_seconds, absl::ToInt64Seconds(Defaults().limits.upload_idle_timeout),
          "an upload stream that brings no byte for this long is closed (it can resume)");
ABSL_FLAG(int, upload_expiry_hours, absl::ToInt64Hours(Defaults().limits.upload_expiry),
          "an unfinished upload nobody has written for this long is removed");
ABSL_FLAG(double, blob_retention_hours, absl::ToDoubleHours(Defaults().blob_retention),
          "blobs no job names and nobody used for this long are removed (0: keep all)");
ABSL_FLAG(double, gc_interval_hours, absl::ToDoubleHours(Defaults().gc_interval),
          "how often retention runs (also once at start)");
ABSL_FLAG(bool, gc_dry_run, Defaults().gc_dry_run,
          "retention lists what it would remove and removes nothing");
ABSL_FLAG(bool, gc_once, false,
          "run one retention pass over --data_dir, print what it removed (or, with "
          "--gc_dry_run, would remove) and exit, without serving");
ABSL_FLAG(int64_t, min_free_disk_mb, Defaults().min_free_disk_bytes >> 20,
          "uploads are refused, and health says NOT_SERVING, while the data folder has less "
          "free space than this");
ABSL_FLAG(int, lease_seconds, absl::ToInt64Seconds(Defaults().lease), "worker lease length");
ABSL_FLAG(int, max_attempts, Defaults().max_attempts,
          "runs before a job whose worker keeps vanishing fails");
ABSL_FLAG(int, heartbeat_seconds, absl::ToInt64Seconds(Defaults().heartbeat), "WatchJob heartbeat");
ABSL_FLAG(bool, cache, Defaults().cache, "reuse results of identical work");
ABSL_FLAG(int, drain_seconds, absl::ToInt64Seconds(sheetmesh::runtime::kDefaultDrain),
          "on SIGTERM, how long running jobs may finish");
ABSL_FLAG(std::string, port_file, "", "write the bound port here once serving (for scripts)");
// --isolate_jobs and the job limits: worker/runtime/job_limit_flags.cc.

namespace {

sheetmesh::server::ServerOptions OptionsFromFlags() {
  sheetmesh::server::ServerOptions o;
  o.address = absl::GetFlag(FLAGS_address);
  o.data_dir = absl::GetFlag(FLAGS_data_dir);
  o.postgres = absl::GetFlag(FLAGS_postgres);
  o.worker_token_file = absl::GetFlag(FLAGS_worker_token_file);
  o.scratch_dir = absl::GetFlag(FLAGS_scratch_dir);
  o.workers = absl::GetFlag(FLAGS_workers);
  o.local_workers = absl::GetFlag(FLAGS_local_workers);
  for (absl::string_view r :
       absl::StrSplit(absl::GetFlag(FLAGS_allowed_root), ',', absl::SkipEmpty())) {
    o.allowed_roots.emplace_back(r);
  }
  o.auth_token = absl::GetFlag(FLAGS_auth_token);
  o.auth_token_file = absl::GetFlag(FLAGS_auth_token_file);
  o.tls_cert = absl::GetFlag(FLAGS_tls_cert);
  o.tls_key = absl::GetFlag(FLAGS_tls_key);
  o.limits.max_blob_bytes = absl::GetFlag(FLAGS_max_blob_bytes);
  o.limits.max_queued_jobs = absl::GetFlag(FLAGS_max_queued_jobs);
  o.limits.max_brick_tasks = absl::GetFlag(FLAGS_max_brick_tasks);
  o.limits.max_unfinished_upload_bytes_per_tenant =
      std::max<int64_t>(1, absl::GetFlag(FLAGS_max_unfinished_upload_mb)) << 20;
  o.limits.max_upload_streams = absl::GetFlag(FLAGS_max_upload_streams);
  o.limits.max_upload_streams_per_client = absl::GetFlag(FLAGS_max_upload_streams_per_client);
  o.limits.max_watch_streams = absl::GetFlag(FLAGS_max_watch_streams);
  o.limits.max_watch_streams_per_client = absl::GetFlag(FLAGS_max_watch_streams_per_client);
  o.limits.upload_idle_timeout =
      absl::Seconds(std::max(1, absl::GetFlag(FLAGS_upload_idle_seconds)));
  o.limits.upload_expiry = absl::Hours(std::max(1, absl::GetFlag(FLAGS_upload_expiry_hours)));
  o.blob_retention = absl::Hours(std::max(0.0, absl::GetFlag(FLAGS_blob_retention_hours)));
  o.gc_interval = absl::Hours(std::max(1.0 / 60, absl::GetFlag(FLAGS_gc_interval_hours)));
  o.gc_dry_run = absl::GetFlag(FLAGS_gc_dry_run);
  o.min_free_disk_bytes = std::max<int64_t>(0, absl::GetFlag(FLAGS_min_free_disk_mb)) << 20;
  o.lease = absl::Seconds(absl::GetFlag(FLAGS_lease_seconds));
  o.max_attempts = absl::GetFlag(FLAGS_max_attempts);
  o.heartbeat = absl::Seconds(absl::GetFlag(FLAGS_heartbeat_seconds));
  o.cache = absl::GetFlag(FLAGS_cache);
  o.isolate_jobs = sheetmesh::runtime::IsolateJobsFromFlags();
  o.job_limits = sheetmesh::runtime::JobLimitsFromFlags();
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  // A job's child process (server.h, isolate_jobs) runs the pipeline and ends here.
  if (const int code = sheetmesh::runtime::RunJobChildIfAsked(argc, argv); code >= 0) return code;
  // Two malloc arenas: upload buffers allocated by gRPC's threads and freed by the
  // handlers' stay in a bounded heap instead of one arena per thread (measured in
  // bench/RESULTS.md, "Service").
  sheetmesh::UseTransparentHugePages(argc, argv, /*max_arenas=*/2);
  absl::SetProgramUsageMessage("sheetmesh-server --data_dir=DIR [flags]");
  if (sheetmesh::WantsVersion(argc, argv)) {
    sheetmesh::PrintVersion("sheetmesh-server", std::cout);
    return 0;
  }
  if (sheetmesh::WantsHelp(argc, argv)) {
    std::cout << "sheetmesh-server --data_dir=DIR [flags]\n\n";
    sheetmesh::PrintFlagsOf("server/main.cc", std::cout);
    sheetmesh::PrintFlagsOf(sheetmesh::runtime::kJobLimitFlagsFile, std::cout);
    return 0;
  }
  sheetmesh::ParseFlagsOrExit(argc, argv, "sheetmesh-server");
  // Every open upload holds descriptors: take the most the system allows this process (the
  // soft limit, often 1024, up to the hard one).
  struct rlimit files;
  if (::getrlimit(RLIMIT_NOFILE, &files) == 0 && files.rlim_cur < files.rlim_max) {
    files.rlim_cur = files.rlim_max;
    ::setrlimit(RLIMIT_NOFILE, &files);
  }
  // Signals go to one thread that waits for them.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  const sheetmesh::server::ServerOptions o = OptionsFromFlags();
  if (absl::GetFlag(FLAGS_gc_once)) {
    if (o.data_dir.empty()) {
      std::cerr << "sheetmesh-server: --gc_once needs --data_dir\n";
      return 2;
    }
    absl::StatusOr<std::string> listing = sheetmesh::server::CollectOnce(o);
    if (!listing.ok()) {
      std::cerr << "sheetmesh-server: " << listing.status() << "\n";
      return 1;
    }
    std::cout << *listing;
    return 0;
  }
  auto server = sheetmesh::server::Server::Start(o);
  if (!server.ok()) {
    std::cerr << "sheetmesh-server: " << server.status() << "\n";
    return server.status().code() == absl::StatusCode::kInvalidArgument ? 2 : 1;
  }
  std::cout << "sheetmesh-server listening on port " << (*server)->port() << ", data in "
            << o.data_dir << std::endl;
  if (!absl::GetFlag(FLAGS_port_file).empty()) {
    // Atomically, so that a script polling for the file never reads half of it.
    const absl::Status st = sheetmesh::WriteFileAtomically(absl::GetFlag(FLAGS_port_file),
                                                           absl::StrCat((*server)->port(), "\n"));
    if (!st.ok()) {
      std::cerr << "sheetmesh-server: " << st << "\n";
      (*server)->Shutdown(absl::ZeroDuration());
      return 1;
    }
  }
  int sig = 0;
  sigwait(&signals, &sig);
  std::cout << "sheetmesh-server: signal " << sig << ", draining" << std::endl;
  (*server)->Shutdown(absl::Seconds(absl::GetFlag(FLAGS_drain_seconds)));
  std::cout << "sheetmesh-server: stopped" << std::endl;
  return 0;
}
