#include "server/server.h"

#include <dirent.h>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/resource_quota.h>
#include <sys/resource.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <atomic>
#include <condition_variable>
#include <filesystem>
#include <iostream>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/strip.h"
#include "absl/time/clock.h"
#include "common/file_util.h"
#include "common/status_macros.h"
#include "server/blob_service.h"
#include "server/bricked_jobs.h"
#include "server/job_service.h"
#include "server/postgres_events.h"
#include "server/retention.h"
#include "server/volume_service.h"
#include "server/worker_service.h"
#include "worker/runtime/worker_pool.h"

namespace sheetmesh::server {
namespace {

// The job store the options name: PostgreSQL, or SQLite in the data folder.
absl::StatusOr<std::unique_ptr<JobStore>> OpenJobStore(const ServerOptions& o) {
  if (!o.postgres.empty()) return OpenPostgresJobStore(o.postgres);
  return OpenSqliteJobStore(o.data_dir + "/jobs.db");
}

// Descriptors this process holds, and its limit.
std::pair<int64_t, int64_t> Descriptors() {
  int64_t open = 0;
  if (DIR* d = ::opendir("/proc/self/fd")) {
    while (::readdir(d) != nullptr) ++open;
    ::closedir(d);
    open -= 3;  // ".", ".." and the folder itself
  }
  struct rlimit rl;
  const int64_t limit = ::getrlimit(RLIMIT_NOFILE, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY
                            ? static_cast<int64_t>(rl.rlim_cur)
                            : INT64_MAX;
  return {open, limit};
}

std::string Slurp(const std::string& path) {
  auto s = ReadFileToString(path);
  return s.ok() ? *s : std::string();
}

}  // namespace

struct Server::Impl {
  ServerOptions options;
  Tenants tenants;
  std::unique_ptr<JobStore> jobs;
  std::unique_ptr<BlobStore> blobs;
  JobEvents events;
  std::unique_ptr<PgEventRelay> relay;  // over PostgreSQL: the other servers' events too
  std::unique_ptr<LocalJobHost> host;
  std::unique_ptr<StreamLimits> upload_streams, watch_streams;
  ServiceContext ctx;
  std::unique_ptr<BlobServiceImpl> blob_service;
  std::unique_ptr<JobServiceImpl> job_service;
  std::unique_ptr<VolumeServiceImpl> volume_service;
  std::unique_ptr<WorkerServiceImpl> worker_service;
  std::unique_ptr<grpc::Server> grpc_server;
  std::unique_ptr<runtime::WorkerPool> pool;
  std::thread housekeeping;  // leases, health, retention
  mutable std::mutex mu;
  std::condition_variable cv;
  bool stopping = false;
  bool stopped = false;
  std::string not_serving;  // why health says NOT_SERVING

  // Requeues jobs whose lease expired, checks what health reports, runs retention.
  void Housekeeping() {
    const absl::Duration tick = std::min(options.lease / 3, absl::Seconds(2));
    absl::Time next_lease = absl::Now(), next_gc = absl::Now();
    std::unique_lock<std::mutex> lock(mu);
    while (!stopping) {
      lock.unlock();
      const absl::Time now = absl::Now();
      if (now >= next_lease) {
        next_lease = now + options.lease / 3;
        std::vector<v1::Job> ended;
        absl::StatusOr<int> n = jobs->RequeueExpired(options.max_attempts, false, false, &ended);
        LostJobsEnded(*jobs, events, ended);
        if (n.ok() && *n > 0) host->WakeWorkers();
      }
      CheckHealth();
      if (options.blob_retention > absl::ZeroDuration() && now >= next_gc) {
        next_gc = now + options.gc_interval;
        absl::StatusOr<RetentionReport> r =
            CollectBlobs(*blobs, *jobs, options.blob_retention, options.gc_dry_run);
        if (!r.ok()) {
          std::cerr << "sheetmesh-server: retention: " << r.status() << std::endl;
        } else if (!r->collected.empty() || options.gc_dry_run) {
          std::cerr << r->Listing() << std::flush;
        }
      }
      lock.lock();
      cv.wait_for(lock, absl::ToChronoMilliseconds(tick), [&] { return stopping; });
    }
  }

  // The gRPC server: the services, TLS, the token gate, message and thread limits.
  absl::Status StartGrpc(int* port) {
    const ServerOptions& o = options;
    grpc::EnableDefaultHealthCheckService(true);
    grpc::reflection::InitProtoReflectionServerBuilderPlugin();
    grpc::ServerBuilder builder;
    std::shared_ptr<grpc::ServerCredentials> creds = grpc::InsecureServerCredentials();
    if (!o.tls_cert.empty()) {
      grpc::SslServerCredentialsOptions ssl;
      ssl.pem_key_cert_pairs.push_back({Slurp(o.tls_key), Slurp(o.tls_cert)});
      creds = grpc::SslServerCredentials(ssl);
    }
    if (!tenants.open()) {
      // Reflection (and any service but health and sheetmesh's own) only with a known token.
      std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>> gates;
      gates.push_back(TokenGate(&tenants));
      builder.experimental().SetInterceptorCreators(std::move(gates));
    }
    builder.AddListeningPort(o.address, creds, port);
    builder.RegisterService(blob_service.get());
    builder.RegisterService(job_service.get());
    builder.RegisterService(volume_service.get());
    builder.RegisterService(worker_service.get());
    builder.SetMaxReceiveMessageSize(o.max_message_bytes);
    builder.SetMaxSendMessageSize(o.max_message_bytes);
    // Synchronous handlers hold a thread each: uploads (bounded by their limit), reads and
    // short calls. Past this, gRPC answers RESOURCE_EXHAUSTED instead of growing threads.
    grpc::ResourceQuota quota("sheetmesh");
    quota.SetMaxThreads(o.limits.max_upload_streams + 256);
    builder.SetResourceQuota(quota);
    // Keepalive: ping idle connections, and let clients ping watch streams that wait long.
    builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, 60000);
    builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 20000);
    builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
    builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS, 10000);
    builder.AddChannelArgument(GRPC_ARG_HTTP2_MAX_PING_STRIKES, 0);
    grpc_server = builder.BuildAndStart();
    if (grpc_server == nullptr || *port == 0) {
      return absl::UnavailableError(absl::StrCat("cannot listen on ", o.address));
    }
    return absl::OkStatus();
  }

  // NOT_SERVING while uploads could not be taken: the disk nearly full, or descriptors
  // nearly all used.
  void CheckHealth() {
    std::string why;
    struct statvfs fs;
    if (::statvfs(options.data_dir.c_str(), &fs) == 0) {
      const int64_t free_bytes = static_cast<int64_t>(fs.f_bavail) * fs.f_frsize;
      if (free_bytes < options.min_free_disk_bytes) {
        why = absl::StrCat(options.data_dir, " has ", free_bytes, " bytes free, below ",
                           options.min_free_disk_bytes, " (--min_free_disk_mb)");
      }
    }
    const auto [open, limit] = Descriptors();
    if (why.empty() && open * 10 > limit * 9) {
      why = absl::StrCat("the server holds ", open, " of its ", limit, " file descriptors");
    }
    std::lock_guard<std::mutex> lock(mu);
    if (why == not_serving || stopping) return;
    if (why.empty()) {
      std::cerr << "sheetmesh-server: serving again" << std::endl;
    } else {
      std::cerr << "sheetmesh-server: NOT_SERVING: " << why << std::endl;
    }
    not_serving = why;
    grpc_server->GetHealthCheckService()->SetServingStatus(why.empty());
  }
};

absl::StatusOr<std::unique_ptr<Server>> Server::Start(const ServerOptions& o) {
  if (o.data_dir.empty())
    return absl::InvalidArgumentError("the server needs a data folder (--data_dir)");
  if (o.tls_cert.empty() != o.tls_key.empty()) {
    return absl::InvalidArgumentError("TLS needs both --tls_cert and --tls_key");
  }
  if (o.max_attempts < 1) {
    return absl::InvalidArgumentError(
        absl::StrCat("max_attempts ", o.max_attempts, " must be at least 1"));
  }
  if (!o.auth_token.empty() && !o.auth_token_file.empty()) {
    return absl::InvalidArgumentError("give --auth_token or --auth_token_file, not both");
  }
  std::unique_ptr<Server> server(new Server());
  server->impl_ = std::make_unique<Impl>();
  Impl& s = *server->impl_;
  s.options = o;
  if (!o.auth_token_file.empty()) {
    SM_ASSIGN_OR_RETURN(s.tenants, Tenants::FromFile(o.auth_token_file));
  } else {
    SM_ASSIGN_OR_RETURN(s.tenants, Tenants::FromToken(o.auth_token));
  }
  if (!o.worker_token_file.empty()) {
    SM_ASSIGN_OR_RETURN(std::string token, ReadFileToString(o.worker_token_file));
    SM_RETURN_IF_ERROR(s.tenants.AddWorkerToken(std::string(absl::StripAsciiWhitespace(token)),
                                                o.worker_token_file));
  }
  SM_RETURN_IF_ERROR(MakeDirs(o.data_dir));
  const std::string scratch = o.scratch_dir.empty() ? o.data_dir + "/scratch" : o.scratch_dir;
  // Nothing runs yet: what the scratch folder holds is left from a previous process (the
  // inputs and outputs of jobs it was running, failed or requeued since).
  std::error_code ec;
  std::filesystem::remove_all(scratch, ec);
  SM_RETURN_IF_ERROR(MakeDirs(scratch));
  SM_ASSIGN_OR_RETURN(s.jobs, OpenJobStore(o));
  if (!o.postgres.empty()) {
    SM_ASSIGN_OR_RETURN(s.relay, PgEventRelay::Start(o.postgres, &s.events));
  }
  SM_ASSIGN_OR_RETURN(s.blobs, BlobStore::Open(o.data_dir + "/blobs"));
  // Jobs that were running when the previous process ended have no worker any more. Over
  // PostgreSQL other servers' workers may be running theirs: only expired leases go back.
  // Isolated jobs cannot take the server down: its death was not theirs, and their lost run
  // does not count against max_attempts.
  std::vector<v1::Job> ended;
  SM_RETURN_IF_ERROR(
      s.jobs
          ->RequeueExpired(o.max_attempts, /*all=*/o.postgres.empty(),
                           /*not_the_jobs_fault=*/o.postgres.empty() && o.isolate_jobs, &ended)
          .status());
  LostJobsEnded(*s.jobs, s.events, ended);
  s.blobs->SetUploadLimits(o.limits.max_unfinished_upload_bytes_per_tenant, o.min_free_disk_bytes);

  LocalJobHostOptions ho;
  ho.allowed_roots = o.allowed_roots;
  ho.scratch_dir = scratch;
  ho.lease = o.lease;
  ho.split = {o.limits.max_brick_tasks, o.limits.max_queued_jobs};
  s.host = std::make_unique<LocalJobHost>(s.jobs.get(), s.blobs.get(), &s.events, ho);
  s.upload_streams = std::make_unique<StreamLimits>("upload", "max_upload_streams",
                                                    o.limits.max_upload_streams_per_client,
                                                    o.limits.max_upload_streams);
  s.watch_streams = std::make_unique<StreamLimits>("watch", "max_watch_streams",
                                                   o.limits.max_watch_streams_per_client,
                                                   o.limits.max_watch_streams);
  s.ctx.jobs = s.jobs.get();
  s.ctx.blobs = s.blobs.get();
  s.ctx.events = &s.events;
  s.ctx.host = s.host.get();
  s.ctx.allowed_roots = o.allowed_roots;
  s.ctx.tenants = &s.tenants;
  s.ctx.worker_lease = o.lease;
  s.ctx.limits = o.limits;
  s.ctx.upload_streams = s.upload_streams.get();
  s.ctx.watch_streams = s.watch_streams.get();
  s.ctx.heartbeat = o.heartbeat;
  s.ctx.cache = o.cache;
  s.ctx.inspect.isolate = o.isolate_jobs;
  s.ctx.inspect.program = o.job_program;
  s.ctx.inspect.scratch_dir = scratch;
  s.ctx.inspect.limits = o.job_limits;
  s.ctx.inspect.limits.wall = std::min(o.job_limits.wall, absl::Minutes(2));
  s.blob_service = std::make_unique<BlobServiceImpl>(&s.ctx);
  s.job_service = std::make_unique<JobServiceImpl>(&s.ctx);
  s.volume_service = std::make_unique<VolumeServiceImpl>(&s.ctx);
  s.worker_service = std::make_unique<WorkerServiceImpl>(&s.ctx);

  SM_RETURN_IF_ERROR(s.StartGrpc(&server->port_));
  s.grpc_server->GetHealthCheckService()->SetServingStatus(true);

  runtime::WorkerPoolOptions wo;
  wo.workers = o.workers;
  wo.name = runtime::UniqueWorkerName("local");
  wo.run.scratch_dir = scratch;
  wo.run.isolate = o.isolate_jobs;
  wo.run.program = o.job_program;
  wo.run.limits = o.job_limits;
  wo.renew_interval = o.lease / 3;
  if (o.local_workers) {
    s.pool = std::make_unique<runtime::WorkerPool>(s.host.get(), wo);
    s.pool->Start();
  }
  s.housekeeping = std::thread([&s] { s.Housekeeping(); });
  return server;
}

std::string Server::not_serving_reason() const {
  std::lock_guard<std::mutex> lock(impl_->mu);
  return impl_->not_serving;
}

absl::StatusOr<std::string> Server::CollectNow() {
  Impl& s = *impl_;
  SM_ASSIGN_OR_RETURN(RetentionReport r, CollectBlobs(*s.blobs, *s.jobs, s.options.blob_retention,
                                                      s.options.gc_dry_run));
  return r.Listing();
}

absl::StatusOr<std::string> CollectOnce(const ServerOptions& o) {
  SM_ASSIGN_OR_RETURN(std::unique_ptr<JobStore> jobs, OpenJobStore(o));
  SM_ASSIGN_OR_RETURN(std::unique_ptr<BlobStore> blobs, BlobStore::Open(o.data_dir + "/blobs"));
  SM_ASSIGN_OR_RETURN(RetentionReport r,
                      CollectBlobs(*blobs, *jobs, o.blob_retention, o.gc_dry_run));
  return r.Listing();
}

void Server::Shutdown(absl::Duration drain) {
  Impl& s = *impl_;
  {
    std::lock_guard<std::mutex> lock(s.mu);
    if (s.stopping) return;
    s.stopping = true;
  }
  s.cv.notify_all();
  // (A server whose start failed half-way has only some of its parts.)
  if (s.grpc_server) s.grpc_server->GetHealthCheckService()->SetServingStatus(false);
  // Drain: no new leases; running jobs finish or go back to the queue.
  if (s.pool) s.pool->Drain(drain);
  if (s.housekeeping.joinable()) s.housekeeping.join();
  s.relay.reset();
  s.events.Close();
  if (s.job_service) s.job_service->StopWatches();  // watch streams end, UNAVAILABLE
  if (s.grpc_server) {
    s.grpc_server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(5));
  }
  {
    std::lock_guard<std::mutex> lock(s.mu);
    s.stopped = true;
  }
  s.cv.notify_all();
}

void Server::Wait() {
  Impl& s = *impl_;
  std::unique_lock<std::mutex> lock(s.mu);
  s.cv.wait(lock, [&] { return s.stopped; });
}

Server::~Server() {
  if (impl_) Shutdown(absl::ZeroDuration());
}

}  // namespace sheetmesh::server
