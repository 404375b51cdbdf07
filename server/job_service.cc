#include "server/job_service.h"

#include <sys/stat.h>

#include <algorithm>
#include <climits>

#include "absl/strings/str_cat.h"
#include "common/sha256.h"
#include "common/status_macros.h"
#include "common/version.h"
#include "server/references.h"
#include "server/status_util.h"
#include "worker/runtime/job_parameters.h"

namespace sheetmesh::server {
namespace {

bool Terminal(v1::JobState s) {
  return s == v1::SUCCEEDED || s == v1::FAILED || s == v1::CANCELLED;
}

}  // namespace

absl::StatusOr<std::string> CacheKey(const v1::CreateJobRequest& r, const std::string& resolved,
                                     const std::string& parameters) {
  std::string identity;
  if (r.input().has_volume_digest()) {
    identity = absl::StrCat("digest:", DigestString(r.input().volume_digest()));
  } else {
    struct stat st;
    if (::stat(resolved.c_str(), &st) != 0)
      return absl::NotFoundError(absl::StrCat(resolved, " vanished"));
    identity = absl::StrCat("path:", resolved, ":", st.st_size, ":", st.st_mtim.tv_sec, ".",
                            st.st_mtim.tv_nsec);
  }
  // The file name tells the format of an upload; the parameters say the rest.
  return Sha256Hex(absl::StrCat(SHEETMESH_VERSION, "\n", identity, "\n", r.input().file_name(),
                                "\n", parameters));
}

absl::StatusOr<v1::Job> JobServiceImpl::Fresh(const std::string& name) {
  SM_ASSIGN_OR_RETURN(v1::Job job, ctx_->jobs->Get(name));
  if (job.state() == v1::RUNNING) {
    if (auto p = ctx_->host->Progress(job.name())) *job.mutable_progress() = *p;
  }
  return job;
}

grpc::Status JobServiceImpl::CreateJob(grpc::ServerContext* context, const v1::CreateJobRequest* r,
                                       v1::Job* response) {
  if (grpc::Status a = CheckAuth(context, ctx_->auth_token); !a.ok()) return a;
  if (r->request_id().empty()) {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                        "request_id is required (a UUID chosen by the client)");
  }
  // A retry of an accepted request gets the same job, whatever the queue holds now.
  absl::StatusOr<std::optional<v1::Job>> existing = ctx_->jobs->FindByRequestId(r->request_id());
  if (!existing.ok()) return ToGrpcStatus(existing.status());
  if (existing->has_value()) {
    absl::StatusOr<v1::Job> fresh = Fresh((*existing)->name());
    *response = fresh.ok() ? *fresh : **existing;
    return grpc::Status::OK;
  }
  const v1::JobInput& in = r->input();
  if (!in.file_name().empty()) {
    const std::string& n = in.file_name();
    if (n == "." || n == ".." || n.find('/') != std::string::npos ||
        n.find('\0') != std::string::npos) {
      return ToGrpcStatus(absl::InvalidArgumentError(absl::StrCat(
          "input.file_name '", n, "' must be a plain file name (like rock.tif), without '/'")));
    }
  }
  std::string resolved;
  if (in.has_volume_digest()) {
    if (absl::Status st = CheckDigest(in.volume_digest()); !st.ok()) {
      return ToGrpcStatus(
          absl::InvalidArgumentError(absl::StrCat("input.volume_digest: ", st.message())));
    }
    if (!ctx_->blobs->Contains(in.volume_digest())) {
      return grpc::Status(grpc::StatusCode::FAILED_PRECONDITION,
                          absl::StrCat("input.volume_digest ", DigestString(in.volume_digest()),
                                       " is not stored; upload it first"));
    }
  } else if (!in.volume_path().empty()) {
    absl::StatusOr<std::string> path = ResolveReference(in.volume_path(), ctx_->allowed_roots);
    if (!path.ok()) return ToGrpcStatus(path.status());
    resolved = *path;
  } else {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                        "input needs volume_digest or volume_path");
  }
  // Parameters are resolved once, now: a mistake is the caller's error, not a failed job,
  // and the worker runs what was resolved.
  absl::StatusOr<std::string> parameters = runtime::ResolveJobParameters(r->parameters(), in);
  if (!parameters.ok()) return ToGrpcStatus(parameters.status());

  v1::Job job;
  job.set_request_id(r->request_id());
  *job.mutable_input() = in;
  *job.mutable_parameters() = r->parameters();
  job.set_pipeline_version(SHEETMESH_VERSION);
  job.set_resolved_parameters(*parameters);
  absl::StatusOr<std::string> key = CacheKey(*r, resolved, *parameters);
  if (!key.ok()) return ToGrpcStatus(key.status());
  if (ctx_->cache && !r->no_cache()) {
    absl::StatusOr<std::optional<v1::Job>> cached = ctx_->jobs->FindCached(*key);
    if (!cached.ok()) return ToGrpcStatus(cached.status());
    if (cached->has_value()) {
      job.set_state(v1::SUCCEEDED);
      job.set_cached_from((*cached)->name());
      *job.mutable_artifacts() = (*cached)->artifacts();
      *job.mutable_start_time() = (*cached)->start_time();
      *job.mutable_end_time() = (*cached)->end_time();
    }
  }
  if (job.state() != v1::SUCCEEDED) {
    absl::StatusOr<int64_t> queued = ctx_->jobs->CountInState(v1::QUEUED);
    if (!queued.ok()) return ToGrpcStatus(queued.status());
    if (*queued >= ctx_->limits.max_queued_jobs) {
      return grpc::Status(
          grpc::StatusCode::RESOURCE_EXHAUSTED,
          absl::StrCat("the queue holds ", *queued, " jobs, the server's limit (max_queued_jobs = ",
                       ctx_->limits.max_queued_jobs, "); retry later"));
    }
  }
  bool created = false;
  absl::StatusOr<v1::Job> stored = ctx_->jobs->Create(job, *key, &created);
  if (!stored.ok()) return ToGrpcStatus(stored.status());
  if (created && stored->state() == v1::QUEUED) ctx_->host->WakeWorkers();
  *response = *stored;
  return grpc::Status::OK;
}

grpc::Status JobServiceImpl::GetJob(grpc::ServerContext* context, const v1::GetJobRequest* r,
                                    v1::Job* response) {
  if (grpc::Status a = CheckAuth(context, ctx_->auth_token); !a.ok()) return a;
  absl::StatusOr<v1::Job> job = Fresh(r->name());
  if (!job.ok()) return ToGrpcStatus(job.status());
  *response = *job;
  return grpc::Status::OK;
}

grpc::Status JobServiceImpl::ListJobs(grpc::ServerContext* context, const v1::ListJobsRequest* r,
                                      v1::ListJobsResponse* response) {
  if (grpc::Status a = CheckAuth(context, ctx_->auth_token); !a.ok()) return a;
  if (r->page_size() < 0) {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                        absl::StrCat("page_size ", r->page_size(), " is negative"));
  }
  const int size = r->page_size() == 0 ? 50 : std::min(r->page_size(), 1000);
  std::string next;
  absl::StatusOr<std::vector<v1::Job>> jobs =
      ctx_->jobs->List(r->state(), size, r->page_token(), &next);
  if (!jobs.ok()) return ToGrpcStatus(jobs.status());
  for (v1::Job& j : *jobs) {
    if (j.state() == v1::RUNNING) {
      if (auto p = ctx_->host->Progress(j.name())) *j.mutable_progress() = *p;
    }
    *response->add_jobs() = std::move(j);
  }
  response->set_next_page_token(next);
  return grpc::Status::OK;
}

grpc::Status JobServiceImpl::CancelJob(grpc::ServerContext* context, const v1::CancelJobRequest* r,
                                       v1::Job* response) {
  if (grpc::Status a = CheckAuth(context, ctx_->auth_token); !a.ok()) return a;
  absl::StatusOr<v1::Job> job = ctx_->jobs->RequestCancel(r->name());
  if (!job.ok()) return ToGrpcStatus(job.status());
  if (job->state() == v1::RUNNING) ctx_->host->MarkCancelled(job->name());
  ctx_->events->Notify(job->name());
  absl::StatusOr<v1::Job> fresh = Fresh(r->name());
  *response = fresh.ok() ? *fresh : *job;
  return grpc::Status::OK;
}

grpc::Status JobServiceImpl::DeleteJob(grpc::ServerContext* context, const v1::DeleteJobRequest* r,
                                       v1::DeleteJobResponse*) {
  if (grpc::Status a = CheckAuth(context, ctx_->auth_token); !a.ok()) return a;
  absl::Status st = ctx_->jobs->Delete(r->name());
  if (st.ok()) ctx_->events->Notify(r->name());
  return ToGrpcStatus(st);
}

grpc::Status JobServiceImpl::WatchJob(grpc::ServerContext* context, const v1::WatchJobRequest* r,
                                      grpc::ServerWriter<v1::WatchJobResponse>* writer) {
  if (grpc::Status a = CheckAuth(context, ctx_->auth_token); !a.ok()) return a;
  uint64_t seen = ctx_->events->Version(r->name());
  absl::StatusOr<v1::Job> job = Fresh(r->name());
  if (!job.ok()) return ToGrpcStatus(job.status());
  v1::WatchJobResponse msg;
  *msg.mutable_job() = *job;
  if (!writer->Write(msg)) return grpc::Status::OK;
  std::string last = job->SerializeAsString();
  int stage_sent = job->state() == v1::RUNNING ? job->progress().stage_index() : 0;
  bool first = true;
  while (!Terminal(job->state())) {
    const uint64_t now = ctx_->events->Wait(r->name(), seen, ctx_->heartbeat);
    if (context->IsCancelled()) return grpc::Status::OK;  // the watcher left; the job goes on
    if (ctx_->events->closed()) {
      return grpc::Status(grpc::StatusCode::UNAVAILABLE,
                          "the server is shutting down; watch again after it restarts");
    }
    const bool changed = now != seen;
    // The job first, then the stage log: every stage before the job's current one is in
    // the log by then (LocalJobHost records a stage before it shows it).
    job = Fresh(r->name());
    if (!job.ok()) return ToGrpcStatus(job.status());
    // The first time, the whole log: a stage may have begun before the job's state said
    // RUNNING in the first message.
    const std::vector<v1::JobProgress> stages =
        ctx_->events->StagesSince(r->name(), first ? 0 : seen);
    first = false;
    seen = now;
    // Stages that started and ended while this watcher slept are still told, in order.
    const int current = job->state() == v1::RUNNING ? job->progress().stage_index() : INT32_MAX;
    for (const v1::JobProgress& stage : stages) {
      if (stage.stage_index() <= stage_sent || stage.stage_index() >= current) continue;
      msg.Clear();
      *msg.mutable_job() = *job;
      msg.mutable_job()->set_state(v1::RUNNING);
      msg.mutable_job()->clear_error();
      msg.mutable_job()->clear_artifacts();
      msg.mutable_job()->clear_end_time();
      *msg.mutable_job()->mutable_progress() = stage;
      stage_sent = stage.stage_index();
      if (!writer->Write(msg)) return grpc::Status::OK;
    }
    if (job->state() == v1::RUNNING)
      stage_sent = std::max(stage_sent, job->progress().stage_index());
    const std::string cur = job->SerializeAsString();
    msg.Clear();
    *msg.mutable_job() = *job;
    msg.set_heartbeat(!changed || cur == last);
    last = cur;
    if (!writer->Write(msg)) return grpc::Status::OK;
  }
  return grpc::Status::OK;
}

}  // namespace sheetmesh::server
