#include "server/worker_service.h"

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "common/excerpt.h"
#include "common/status_macros.h"
#include "server/auth.h"
#include "server/blob_service.h"
#include "server/bricked_jobs.h"
#include "server/job_events.h"
#include "server/job_store.h"
#include "server/local_job_host.h"
#include "server/status_util.h"
#include "sheetmesh/v1/job_states.h"

namespace sheetmesh::server {
namespace {

// A name a client may save the artifact under: no folder, no hidden file, no control bytes.
bool IsArtifactName(const std::string& name) {
  if (name.empty() || name.size() > 255 || name[0] == '.') return false;
  for (char c : name) {
    if (!(absl::ascii_isalnum(c) || c == '.' || c == '_' || c == '-')) return false;
  }
  return true;
}

grpc::Status NeedNames(const std::string& name, const std::string& worker) {
  if (worker.empty()) {
    return ToGrpcStatus(absl::InvalidArgumentError("worker is required (the worker's name)"));
  }
  if (name.rfind("jobs/", 0) != 0) {
    return ToGrpcStatus(
        absl::InvalidArgumentError(absl::StrCat("name '", name, "' is not a job name (jobs/ID)")));
  }
  return grpc::Status::OK;
}

}  // namespace

grpc::Status WorkerServiceImpl::Authorize(const grpc::ServerContext& context) const {
  std::string tenant;
  grpc::Status st = ctx_->tenants->Authenticate(context, &tenant);
  if (ctx_->tenants->has_worker_tokens()) {
    if (st.ok() && tenant == Tenants::kWorkerTenant) return grpc::Status::OK;
    return ToGrpcStatus(absl::UnauthenticatedError(
        "a worker needs the server's worker token (--worker_token_file)"));
  }
  if (ctx_->tenants->open()) return grpc::Status::OK;
  return ToGrpcStatus(absl::PermissionDeniedError(
      "this server takes no remote workers: start it with --worker_token_file"));
}

bool WorkerServiceImpl::MustStop(const std::string& job) const {
  absl::StatusOr<bool> stop = ctx_->jobs->CancelRequested(job);
  return !stop.ok() || *stop;
}

std::string WorkerServiceImpl::ParentOf(const std::string& job) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (auto it = parent_.find(job); it != parent_.end()) return it->second;
  }
  absl::StatusOr<v1::Job> j = ctx_->jobs->Get(job);
  if (!j.ok()) return "";
  std::lock_guard<std::mutex> lock(mu_);
  return parent_[job] = j->bricks().parent();
}

grpc::Status WorkerServiceImpl::LeaseJob(grpc::ServerContext* context,
                                         const v1::LeaseJobRequest* request,
                                         v1::LeaseJobResponse* response) {
  if (grpc::Status a = Authorize(*context); !a.ok()) return a;
  if (request->worker().empty()) {
    return ToGrpcStatus(absl::InvalidArgumentError("worker is required (the worker's name)"));
  }
  // A split job comes back for its merge, or ends at the lease when a brick did not succeed:
  // then the next one.
  for (;;) {
    absl::StatusOr<std::optional<v1::Job>> job =
        ctx_->jobs->LeaseNext(request->worker(), ctx_->worker_lease);
    if (!job.ok()) return ToGrpcStatus(job.status());
    if (!job->has_value()) break;
    const std::string name = (*job)->name();
    job = PrepareMerge(*ctx_->jobs, **std::move(job), request->worker());
    if (!job.ok()) return ToGrpcStatus(job.status());
    if (!job->has_value()) {
      ctx_->events->NotifyFinished(name);
      continue;
    }
    *response->mutable_job() = **job;
    ctx_->events->Notify(name);
    break;
  }
  response->set_lease_milliseconds(absl::ToInt64Milliseconds(ctx_->worker_lease));
  return grpc::Status::OK;
}

grpc::Status WorkerServiceImpl::RenewLease(grpc::ServerContext* context,
                                           const v1::RenewLeaseRequest* request,
                                           v1::RenewLeaseResponse* response) {
  if (grpc::Status a = Authorize(*context); !a.ok()) return a;
  if (grpc::Status n = NeedNames(request->name(), request->worker()); !n.ok()) return n;
  absl::Status st = ctx_->jobs->Renew(request->name(), request->worker(), ctx_->worker_lease);
  if (absl::IsFailedPrecondition(st) || absl::IsNotFound(st)) {
    response->set_stop(true);  // gone elsewhere or ended: the worker stops
    return grpc::Status::OK;
  }
  if (!st.ok()) return ToGrpcStatus(st);
  const absl::StatusOr<bool> cancelled = ctx_->jobs->CancelRequested(request->name());
  response->set_stop(!cancelled.ok() || *cancelled);
  response->set_cancelled(cancelled.ok() && *cancelled);
  return grpc::Status::OK;
}

grpc::Status WorkerServiceImpl::ReportProgress(grpc::ServerContext* context,
                                               const v1::ReportProgressRequest* request,
                                               v1::ReportProgressResponse* response) {
  if (grpc::Status a = Authorize(*context); !a.ok()) return a;
  if (grpc::Status n = NeedNames(request->name(), request->worker()); !n.ok()) return n;
  absl::Status st =
      ctx_->jobs->SetProgress(request->name(), request->worker(), request->progress());
  if (absl::IsFailedPrecondition(st) || absl::IsNotFound(st)) {
    response->set_stop(true);
    return grpc::Status::OK;
  }
  if (!st.ok()) return ToGrpcStatus(st);
  bool new_stage = false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    int& last = stage_[request->name()];
    new_stage = request->progress().stage_index() != last;
    last = request->progress().stage_index();
  }
  if (new_stage) {
    ctx_->events->NotifyStage(request->name(), request->progress());
  } else {
    ctx_->events->Notify(request->name());
  }
  // A brick's progress is its job's too.
  if (const std::string parent = ParentOf(request->name()); !parent.empty()) {
    ctx_->events->Notify(parent);
  }
  response->set_stop(MustStop(request->name()));
  return grpc::Status::OK;
}

grpc::Status WorkerServiceImpl::FinishJob(grpc::ServerContext* context,
                                          const v1::FinishJobRequest* request, v1::Job* response) {
  if (grpc::Status a = Authorize(*context); !a.ok()) return a;
  if (grpc::Status n = NeedNames(request->name(), request->worker()); !n.ok()) return n;
  const v1::JobState state = request->state();
  if (!v1::IsTerminal(state)) {
    return ToGrpcStatus(absl::InvalidArgumentError(
        absl::StrCat("state ", v1::JobState_Name(state),
                     " does not end a job (SUCCEEDED, FAILED or CANCELLED)")));
  }
  for (const v1::Artifact& a : request->artifacts()) {
    if (absl::Status st = CheckArtifact(a, request->name()); !st.ok()) return ToGrpcStatus(st);
  }
  absl::StatusOr<v1::Job> done =
      ctx_->jobs->Finish(request->name(), request->worker(), state, request->error(),
                         {request->artifacts().begin(), request->artifacts().end()});
  if (!done.ok()) return ToGrpcStatus(done.status());
  {
    std::lock_guard<std::mutex> lock(mu_);
    stage_.erase(request->name());
    parent_.erase(request->name());
  }
  ctx_->events->NotifyFinished(request->name());
  TaskEnded(*ctx_->jobs, *ctx_->events, *done);
  *response = *done;
  return grpc::Status::OK;
}

absl::Status WorkerServiceImpl::CheckArtifact(const v1::Artifact& a, const std::string& job) const {
  // Every artifact has a plain file name, and is a blob this job's worker uploaded for this
  // job (with worker tokens: an open server has one tenant), stored already.
  if (!IsArtifactName(a.name())) {
    return absl::InvalidArgumentError(
        absl::StrCat("artifact name '", Excerpt(a.name(), 80),
                     "' is not a plain file name ([A-Za-z0-9._-], not starting "
                     "with '.', at most 255 characters)"));
  }
  SM_RETURN_IF_ERROR(CheckDigest(a.digest()));
  if (ctx_->tenants->has_worker_tokens()) {
    SM_ASSIGN_OR_RETURN(const bool owned,
                        ctx_->jobs->OwnsBlob(ArtifactOwner(job), a.digest().hash()));
    if (!owned) {
      return absl::PermissionDeniedError(
          absl::StrCat("artifact ", a.name(), " (", DigestString(a.digest()),
                       ") was not uploaded for ", job, " by its worker"));
    }
  }
  if (!ctx_->blobs->Contains(a.digest())) {
    return absl::FailedPreconditionError(
        absl::StrCat("artifact ", a.name(), " (", a.digest().hash(), "/", a.digest().size_bytes(),
                     ") is not stored: upload it first"));
  }
  return absl::OkStatus();
}

grpc::Status WorkerServiceImpl::SplitJob(grpc::ServerContext* context,
                                         const v1::SplitJobRequest* request, v1::Job* response) {
  if (grpc::Status a = Authorize(*context); !a.ok()) return a;
  if (grpc::Status n = NeedNames(request->name(), request->worker()); !n.ok()) return n;
  if (absl::Status st = CheckArtifact(request->plan(), request->name()); !st.ok()) {
    return ToGrpcStatus(st);
  }
  if (absl::Status st = CheckSplit(*ctx_->jobs,
                                  {ctx_->limits.max_brick_tasks, ctx_->limits.max_queued_jobs},
                                  request->name(), request->count());
      !st.ok()) {
    return ToGrpcStatus(st);
  }
  absl::StatusOr<v1::Job> split =
      ctx_->jobs->Split(request->name(), request->worker(), request->plan(), request->count());
  if (!split.ok()) return ToGrpcStatus(split.status());
  {
    std::lock_guard<std::mutex> lock(mu_);
    stage_.erase(request->name());
  }
  ctx_->events->Notify(request->name());
  if (ctx_->host != nullptr) ctx_->host->WakeWorkers();  // the bricks are queued
  *response = *split;
  return grpc::Status::OK;
}

grpc::Status WorkerServiceImpl::ReleaseJob(grpc::ServerContext* context,
                                           const v1::ReleaseJobRequest* request,
                                           v1::ReleaseJobResponse*) {
  if (grpc::Status a = Authorize(*context); !a.ok()) return a;
  if (grpc::Status n = NeedNames(request->name(), request->worker()); !n.ok()) return n;
  if (absl::Status st = ctx_->jobs->Release(request->name(), request->worker()); !st.ok()) {
    return ToGrpcStatus(st);
  }
  {
    std::lock_guard<std::mutex> lock(mu_);
    stage_.erase(request->name());
    parent_.erase(request->name());
  }
  ctx_->events->Notify(request->name());
  if (ctx_->host != nullptr) ctx_->host->WakeWorkers();
  return grpc::Status::OK;
}

}  // namespace sheetmesh::server
