#include "server/server.h"

#include <filesystem>

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>

#include <atomic>
#include <condition_variable>

#include "absl/strings/str_cat.h"
#include "common/file_util.h"
#include "common/status_macros.h"
#include "server/blob_service.h"
#include "server/job_service.h"
#include "server/volume_service.h"
#include "worker/runtime/worker_pool.h"

namespace sheetmesh::server {

struct Server::Impl {
  ServerOptions options;
  std::unique_ptr<JobStore> jobs;
  std::unique_ptr<BlobStore> blobs;
  JobEvents events;
  std::unique_ptr<LocalJobHost> host;
  ServiceContext ctx;
  std::unique_ptr<BlobServiceImpl> blob_service;
  std::unique_ptr<JobServiceImpl> job_service;
  std::unique_ptr<VolumeServiceImpl> volume_service;
  std::unique_ptr<grpc::Server> grpc_server;
  std::unique_ptr<runtime::WorkerPool> pool;
  std::thread leases;  // requeues jobs whose lease expired
  std::mutex mu;
  std::condition_variable cv;
  bool stopping = false;
  bool stopped = false;

  void WatchLeases() {
    std::unique_lock<std::mutex> lock(mu);
    while (!stopping) {
      cv.wait_for(lock, absl::ToChronoMilliseconds(options.lease / 3), [&] { return stopping; });
      if (stopping) break;
      lock.unlock();
      absl::StatusOr<int> n = jobs->RequeueExpired(options.max_attempts, false);
      if (n.ok() && *n > 0) host->WakeWorkers();
      lock.lock();
    }
  }
};

static std::string Slurp(const std::string& path) {
  auto s = ReadFileToString(path);
  return s.ok() ? *s : std::string();
}

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
  std::unique_ptr<Server> server(new Server());
  server->impl_ = std::make_unique<Impl>();
  Impl& s = *server->impl_;
  s.options = o;
  SM_RETURN_IF_ERROR(MakeDirs(o.data_dir));
  // Nothing runs yet: what the scratch folder holds is left from a previous process (the
  // inputs and outputs of jobs it was running, failed or requeued since).
  std::error_code ec;
  std::filesystem::remove_all(o.data_dir + "/scratch", ec);
  SM_RETURN_IF_ERROR(MakeDirs(o.data_dir + "/scratch"));
  SM_ASSIGN_OR_RETURN(s.jobs, OpenSqliteJobStore(o.data_dir + "/jobs.db"));
  SM_ASSIGN_OR_RETURN(s.blobs, BlobStore::Open(o.data_dir + "/blobs"));
  // Jobs that were running when the previous process ended have no worker any more.
  SM_RETURN_IF_ERROR(s.jobs->RequeueExpired(o.max_attempts, /*all=*/true).status());

  LocalJobHostOptions ho;
  ho.allowed_roots = o.allowed_roots;
  ho.scratch_dir = o.data_dir + "/scratch";
  ho.lease = o.lease;
  s.host = std::make_unique<LocalJobHost>(s.jobs.get(), s.blobs.get(), &s.events, ho);
  s.ctx.jobs = s.jobs.get();
  s.ctx.blobs = s.blobs.get();
  s.ctx.events = &s.events;
  s.ctx.host = s.host.get();
  s.ctx.allowed_roots = o.allowed_roots;
  s.ctx.auth_token = o.auth_token;
  s.ctx.limits = o.limits;
  s.ctx.heartbeat = o.heartbeat;
  s.ctx.cache = o.cache;
  s.blob_service = std::make_unique<BlobServiceImpl>(&s.ctx);
  s.job_service = std::make_unique<JobServiceImpl>(&s.ctx);
  s.volume_service = std::make_unique<VolumeServiceImpl>(&s.ctx);

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  std::shared_ptr<grpc::ServerCredentials> creds = grpc::InsecureServerCredentials();
  if (!o.tls_cert.empty()) {
    grpc::SslServerCredentialsOptions ssl;
    ssl.pem_key_cert_pairs.push_back({Slurp(o.tls_key), Slurp(o.tls_cert)});
    creds = grpc::SslServerCredentials(ssl);
  }
  builder.AddListeningPort(o.address, creds, &server->port_);
  builder.RegisterService(s.blob_service.get());
  builder.RegisterService(s.job_service.get());
  builder.RegisterService(s.volume_service.get());
  builder.SetMaxReceiveMessageSize(o.max_message_bytes);
  builder.SetMaxSendMessageSize(o.max_message_bytes);
  // Keepalive: ping idle connections, and let clients ping watch streams that wait long.
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, 60000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 20000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS, 10000);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MAX_PING_STRIKES, 0);
  s.grpc_server = builder.BuildAndStart();
  if (s.grpc_server == nullptr || server->port_ == 0) {
    return absl::UnavailableError(absl::StrCat("cannot listen on ", o.address));
  }
  s.grpc_server->GetHealthCheckService()->SetServingStatus(true);

  runtime::WorkerPoolOptions wo;
  wo.workers = o.workers;
  wo.name = absl::StrCat("local-", ::getpid());
  wo.run.scratch_dir = o.data_dir + "/scratch";
  wo.run.isolate = o.isolate_jobs;
  wo.run.program = o.job_program;
  wo.run.limits = o.job_limits;
  wo.renew_interval = o.lease / 3;
  s.pool = std::make_unique<runtime::WorkerPool>(s.host.get(), wo);
  s.pool->Start();
  s.leases = std::thread([&s] { s.WatchLeases(); });
  return server;
}

void Server::Shutdown(absl::Duration drain) {
  Impl& s = *impl_;
  {
    std::lock_guard<std::mutex> lock(s.mu);
    if (s.stopping) return;
    s.stopping = true;
  }
  s.cv.notify_all();
  s.grpc_server->GetHealthCheckService()->SetServingStatus(false);
  // Drain: no new leases; running jobs finish or go back to the queue.
  s.pool->Drain(drain);
  if (s.leases.joinable()) s.leases.join();
  s.events.Close();  // watch streams end
  s.grpc_server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(5));
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
