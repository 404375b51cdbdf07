#include "worker/remote/remote_job_host.h"

#include <grpcpp/channel.h>
#include <unistd.h>

#include <filesystem>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_replace.h"
#include "absl/time/clock.h"
#include "common/file_util.h"
#include "common/paths.h"
#include "common/status_macros.h"
#include "google/protobuf/util/time_util.h"

namespace sheetmesh::remote {

using client::FromGrpc;

absl::StatusOr<std::unique_ptr<RemoteJobHost>> RemoteJobHost::Connect(RemoteJobHostOptions o) {
  if (o.scratch_dir.empty()) return absl::InvalidArgumentError("--scratch_dir is required");
  std::unique_ptr<RemoteJobHost> h(new RemoteJobHost(std::move(o)));
  SM_ASSIGN_OR_RETURN(h->client_, client::SheetmeshClient::Connect(h->options_.server));
  h->workers_ = v1::WorkerService::NewStub(h->client_->channel());
  SM_RETURN_IF_ERROR(MakeDirs(h->options_.scratch_dir));
  // Through the host's one channel (the client's calls are thread-safe); the cache goes
  // before the client.
  client::SheetmeshClient* c = h->client_.get();
  h->cache_ = std::make_unique<BlobCache>(
      h->options_.scratch_dir + "/cache",
      [c](const v1::Digest& d, const std::string& path) { return c->Download(d, path); },
      [c](const v1::Digest& d, int64_t offset, int64_t length,
          const std::function<absl::Status(absl::string_view)>& sink) {
        return c->ReadRange(d, offset, length, sink);
      });
  // One call that changes nothing, to find a wrong address or token now, not in a loop.
  v1::RenewLeaseRequest probe;
  probe.set_name("jobs/none");
  probe.set_worker("probe");
  v1::RenewLeaseResponse ignored;
  auto ctx = h->Context();
  ctx->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(20));
  SM_RETURN_IF_ERROR(FromGrpc(h->workers_->RenewLease(ctx.get(), probe, &ignored),
                              absl::StrCat("the server at ", h->options_.server.address)));
  return h;
}

void RemoteJobHost::Stop() {
  std::lock_guard<std::mutex> lock(mu_);
  stopping_ = true;
  stop_cv_.notify_all();
}

absl::StatusOr<std::optional<v1::Job>> RemoteJobHost::Lease(const std::string& worker,
                                                            absl::Duration wait) {
  const absl::Time deadline = absl::Now() + wait;
  for (;;) {
    v1::LeaseJobRequest req;
    req.set_worker(worker);
    v1::LeaseJobResponse resp;
    auto ctx = Context();
    ctx->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    grpc::Status s = workers_->LeaseJob(ctx.get(), req, &resp);
    if (!s.ok()) return FromGrpc(s, absl::StrCat("leasing from ", options_.server.address));
    if (resp.has_job()) {
      std::lock_guard<std::mutex> lock(mu_);
      live_[resp.job().name()] = Live{};
      return std::optional<v1::Job>(resp.job());
    }
    std::unique_lock<std::mutex> lock(mu_);
    const absl::Duration left = deadline - absl::Now();
    if (stopping_ || left <= absl::ZeroDuration()) return std::optional<v1::Job>();
    stop_cv_.wait_for(lock, absl::ToChronoMilliseconds(std::min(left, options_.lease_poll)),
                      [&] { return stopping_; });
  }
}

absl::Status RemoteJobHost::Renew(const std::string& job, const std::string& worker) {
  v1::RenewLeaseRequest req;
  req.set_name(job);
  req.set_worker(worker);
  v1::RenewLeaseResponse resp;
  auto ctx = Context();
  SM_RETURN_IF_ERROR(FromGrpc(workers_->RenewLease(ctx.get(), req, &resp), "renewing " + job));
  if (resp.stop() && resp.cancelled()) {
    return absl::CancelledError(absl::StrCat(job, " was cancelled"));
  }
  if (resp.stop()) {
    return absl::FailedPreconditionError(
        absl::StrCat(job, ": the server says stop (the job ended, or its lease went elsewhere)"));
  }
  return absl::OkStatus();
}

bool RemoteJobHost::ReportProgress(const std::string& job, const std::string& worker,
                                   const runtime::ProgressUpdate& u) {
  const absl::Time now = absl::Now();
  {
    std::lock_guard<std::mutex> lock(mu_);
    Live& live = live_[job];
    if (u.stage_index == live.stage && now - live.reported < options_.progress_interval) {
      return true;
    }
    live.stage = u.stage_index;
    live.reported = now;
  }
  v1::ReportProgressRequest req;
  req.set_name(job);
  req.set_worker(worker);
  v1::JobProgress* p = req.mutable_progress();
  p->set_stage(u.stage);
  p->set_stage_index(u.stage_index);
  p->set_stage_count(u.stage_count);
  p->set_fraction(u.fraction);
  p->set_message(u.message);
  *p->mutable_update_time() =
      google::protobuf::util::TimeUtil::MillisecondsToTimestamp(absl::ToUnixMillis(now));
  v1::ReportProgressResponse resp;
  auto ctx = Context();
  ctx->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  // A server that does not answer now may later: the lease's renewal decides.
  if (!workers_->ReportProgress(ctx.get(), req, &resp).ok()) return true;
  return !resp.stop();
}

void RemoteJobHost::Forget(const std::string& job) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    live_.erase(job);
  }
  std::error_code ec;
  std::filesystem::remove_all(InputDir(job), ec);
  cache_->Release(job);
}

std::string RemoteJobHost::InputDir(const std::string& job) const {
  return absl::StrCat(options_.scratch_dir, "/inputs/", absl::StrReplaceAll(job, {{"/", "-"}}));
}

absl::StatusOr<runtime::LocalVolume> RemoteJobHost::ResolveInput(
    const v1::Job& job, const std::vector<runtime::ByteRange>* only) {
  const v1::JobInput& in = job.input();
  runtime::LocalVolume v;
  if (in.has_volume_digest()) {
    const std::string name = runtime::InputFileName(in);
    const std::string dir = InputDir(job.name());
    SM_RETURN_IF_ERROR(MakeDirs(dir));
    v.path = dir + "/" + name;
    // Readers tell formats by name: the cached copy under the client's file name.
    SM_ASSIGN_OR_RETURN(const std::string cached,
                        cache_->Get(job.name(), in.volume_digest(), only));
    ::unlink(v.path.c_str());
    if (::symlink(cached.c_str(), v.path.c_str()) != 0) return ErrnoStatus(errno, v.path);
    v.display_name = in.file_name().empty() ? in.volume_digest().hash() : in.file_name();
    return v;
  }
  if (in.has_volume_files()) {
    const std::string dir = InputDir(job.name()) + "/" + runtime::InputFolderName(in);
    SM_ASSIGN_OR_RETURN(auto c, client::SheetmeshClient::Connect(options_.server));
    SM_ASSIGN_OR_RETURN(
        v.path, runtime::LayOutVolumeFiles(in.volume_files(), dir,
                                           [&](const v1::Digest& d, const std::string& path) {
                                             return c->Download(d, path);
                                           }));
    v.display_name = runtime::InputFolderName(in);
    // A detached header's data file must be one of the volume's own files.
    v.data_files = true;
    v.data_file_roots = {dir};
    return v;
  }
  if (!in.volume_path().empty()) {
    // A path names shared storage: this worker must see it under its own roots.
    SM_ASSIGN_OR_RETURN(v.path, ResolveUnderRoots(in.volume_path(), options_.allowed_roots,
                                                  "volume_path (on this worker)"));
    v.display_name = in.volume_path();
    v.data_files = true;
    v.data_file_roots = options_.allowed_roots;
    return v;
  }
  return absl::InvalidArgumentError(absl::StrCat(job.name(), ": input names no volume"));
}

absl::StatusOr<v1::Artifact> RemoteJobHost::PutArtifact(const std::string& job,
                                                        const std::string& worker,
                                                        const std::string& path,
                                                        const std::string& media_type) {
  // The upload says whose output it is: the server records it as the job's, and takes as
  // the job's artifacts only blobs so uploaded.
  client::ClientOptions o = options_.server;
  o.artifact_job = job;
  o.artifact_worker = worker;
  SM_ASSIGN_OR_RETURN(auto c, client::SheetmeshClient::Connect(o));
  SM_ASSIGN_OR_RETURN(v1::Digest d, c->Upload(path));
  v1::Artifact a;
  *a.mutable_digest() = d;
  a.set_media_type(media_type);
  return a;
}

absl::Status RemoteJobHost::Finish(const std::string& job, const std::string& worker,
                                   const absl::Status& result,
                                   const std::vector<v1::Artifact>& artifacts) {
  v1::FinishJobRequest req;
  req.set_name(job);
  req.set_worker(worker);
  req.set_state(runtime::EndStateOf(result));
  *req.mutable_error() = runtime::ErrorOf(result);
  for (const v1::Artifact& a : artifacts) *req.add_artifacts() = a;
  v1::Job done;
  auto ctx = Context();
  absl::Status st = FromGrpc(workers_->FinishJob(ctx.get(), req, &done), "finishing " + job);
  Forget(job);
  return st;
}

absl::Status RemoteJobHost::Release(const std::string& job, const std::string& worker) {
  v1::ReleaseJobRequest req;
  req.set_name(job);
  req.set_worker(worker);
  v1::ReleaseJobResponse resp;
  auto ctx = Context();
  absl::Status st = FromGrpc(workers_->ReleaseJob(ctx.get(), req, &resp), "releasing " + job);
  Forget(job);
  return st;
}

absl::Status RemoteJobHost::Split(const std::string& job, const std::string& worker,
                                  const v1::Artifact& plan, int count) {
  v1::SplitJobRequest req;
  req.set_name(job);
  req.set_worker(worker);
  *req.mutable_plan() = plan;
  req.set_count(count);
  v1::Job split;
  auto ctx = Context();
  absl::Status st = FromGrpc(workers_->SplitJob(ctx.get(), req, &split), "splitting " + job);
  Forget(job);
  return st;
}

absl::Status RemoteJobHost::FetchBlob(const v1::Digest& digest, const std::string& path) {
  SM_ASSIGN_OR_RETURN(auto c, client::SheetmeshClient::Connect(options_.server));
  return c->Download(digest, path);
}

}  // namespace sheetmesh::remote
