#include "server/job_service.h"

#include <sys/stat.h>

#include <algorithm>
#include <climits>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "common/sha256.h"
#include "common/status_macros.h"
#include "common/version.h"
#include "server/bricked_jobs.h"
#include "server/references.h"
#include "server/status_util.h"
#include "server/watch_job.h"
#include "worker/pipeline/volume/hdf5_io.h"
#include "worker/runtime/job_host.h"
#include "worker/runtime/job_parameters.h"

namespace sheetmesh::server {
namespace {

// A request id is the client's: printable, and short enough for an index.
absl::Status CheckRequestId(const std::string& id) {
  if (id.empty()) {
    return absl::InvalidArgumentError("request_id is required (a UUID chosen by the client)");
  }
  if (id.size() > 256) {
    return absl::InvalidArgumentError(
        absl::StrCat("request_id of ", id.size(), " characters is longer than 256"));
  }
  for (unsigned char c : id) {
    if (c < 0x20 || c == 0x7f) {
      return absl::InvalidArgumentError(
          absl::StrCat("request_id holds the control character ", int{c}, "; use a UUID"));
    }
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<std::string> CacheKey(const std::string& tenant, const v1::CreateJobRequest& r,
                                     const std::string& resolved, const std::string& parameters) {
  std::string identity;
  if (r.input().has_volume_digest()) {
    identity = absl::StrCat("digest:", DigestString(r.input().volume_digest()));
  } else if (r.input().has_volume_files()) {
    // The files by name and content, in name order: a manifest listed in another order
    // is the same volume.
    std::vector<std::string> lines;
    for (const v1::VolumeFiles::File& f : r.input().volume_files().files()) {
      lines.push_back(absl::StrCat(f.name(), "\t", DigestString(f.digest())));
    }
    std::sort(lines.begin(), lines.end());
    identity = absl::StrCat("files:", r.input().volume_files().main(), "\n",
                            Sha256Hex(absl::StrJoin(lines, "\n")));
  } else {
    // "scan.h5:/entry/data": the file's state, the dataset by name.
    const auto hdf5 = SplitHdf5Path(resolved);
    const std::string file = hdf5 ? hdf5->first : resolved;
    struct stat st;
    if (::stat(file.c_str(), &st) != 0) return absl::NotFoundError(absl::StrCat(file, " vanished"));
    identity = absl::StrCat("path:", resolved, ":", st.st_size, ":", st.st_mtim.tv_sec, ".",
                            st.st_mtim.tv_nsec);
  }
  // The file name tells the format of an upload; the parameters say the rest.
  // A tenant's results are reused for that tenant only.
  return Sha256Hex(absl::StrCat(SHEETMESH_VERSION, "\n", tenant, "\n", identity, "\n",
                                r.input().file_name(), "\n", parameters));
}

JobServiceImpl::JobServiceImpl(const ServiceContext* ctx)
    : ctx_(ctx), hub_(std::make_unique<WatchHub>(ctx)) {}

JobServiceImpl::~JobServiceImpl() { StopWatches(); }

void JobServiceImpl::StopWatches() { hub_->Stop(); }

grpc::ServerWriteReactor<v1::WatchJobResponse>* JobServiceImpl::WatchJob(
    grpc::CallbackServerContext* context, const v1::WatchJobRequest* request) {
  return hub_->Watch(context, *request);
}

absl::StatusOr<bool> JobServiceImpl::Usable(const std::string& tenant, const v1::Digest& digest) {
  // Another tenant's blob is, to this one, not stored.
  if (!ctx_->blobs->Contains(digest)) return false;
  if (ctx_->tenants->open()) return true;
  return ctx_->jobs->OwnsBlob(tenant, digest.hash());
}

absl::Status JobServiceImpl::CheckInput(const std::string& tenant, const v1::JobInput& in,
                                        std::string* resolved) {
  if (!in.file_name().empty()) {
    const std::string& n = in.file_name();
    if (n == "." || n == ".." || n.find('/') != std::string::npos ||
        n.find('\0') != std::string::npos) {
      return absl::InvalidArgumentError(absl::StrCat(
          "input.file_name '", n, "' must be a plain file name (like rock.tif), without '/'"));
    }
  }
  if (in.has_volume_digest()) {
    if (absl::Status st = CheckDigest(in.volume_digest()); !st.ok()) {
      return absl::InvalidArgumentError(absl::StrCat("input.volume_digest: ", st.message()));
    }
    SM_ASSIGN_OR_RETURN(const bool usable, Usable(tenant, in.volume_digest()));
    if (!usable) {
      return absl::FailedPreconditionError(absl::StrCat("input.volume_digest ",
                                                        DigestString(in.volume_digest()),
                                                        " is not stored; upload it first"));
    }
    ctx_->blobs->Touch(in.volume_digest());
    return absl::OkStatus();
  }
  if (in.has_volume_files()) {
    const v1::VolumeFiles& files = in.volume_files();
    SM_RETURN_IF_ERROR(runtime::CheckVolumeFiles(files, "input.volume_files"));
    std::vector<std::string> missing;
    for (int i = 0; i < files.files_size(); ++i) {
      const v1::Digest& d = files.files(i).digest();
      if (absl::Status st = CheckDigest(d); !st.ok()) {
        return absl::InvalidArgumentError(absl::StrCat("input.volume_files.files[", i, "] ('",
                                                       files.files(i).name(),
                                                       "').digest: ", st.message()));
      }
      SM_ASSIGN_OR_RETURN(const bool usable, Usable(tenant, d));
      if (!usable) missing.push_back(files.files(i).name());
    }
    if (!missing.empty()) {
      return absl::FailedPreconditionError(
          absl::StrCat("input.volume_files: ", missing.size(), " of ", files.files_size(),
                       " files are not stored (",
                       absl::StrJoin(missing.begin(),
                                     missing.begin() + std::min<size_t>(5, missing.size()), ", "),
                       missing.size() > 5 ? ", ..." : "", "); upload them first"));
    }
    for (const v1::VolumeFiles::File& f : files.files()) ctx_->blobs->Touch(f.digest());
    return absl::OkStatus();
  }
  if (!in.volume_path().empty()) {
    SM_ASSIGN_OR_RETURN(*resolved, ResolveReference(in.volume_path(), ctx_->allowed_roots));
    return absl::OkStatus();
  }
  return absl::InvalidArgumentError("input needs volume_digest, volume_files or volume_path");
}

grpc::Status JobServiceImpl::CreateJob(grpc::ServerContext* context, const v1::CreateJobRequest* r,
                                       v1::Job* response) {
  std::string tenant;
  if (grpc::Status a = ctx_->tenants->Authenticate(*context, &tenant); !a.ok()) return a;
  if (absl::Status st = CheckRequestId(r->request_id()); !st.ok()) return ToGrpcStatus(st);
  // A retry of an accepted request gets the same job, whatever the queue holds now.
  absl::StatusOr<std::optional<v1::Job>> existing =
      ctx_->jobs->FindByRequestId(tenant, r->request_id());
  if (!existing.ok()) return ToGrpcStatus(existing.status());
  if (existing->has_value()) {
    absl::StatusOr<v1::Job> fresh = FreshJob(*ctx_, tenant, (*existing)->name());
    *response = fresh.ok() ? *fresh : **existing;
    return grpc::Status::OK;
  }
  const v1::JobInput& in = r->input();
  std::string resolved;
  if (absl::Status st = CheckInput(tenant, in, &resolved); !st.ok()) return ToGrpcStatus(st);
  // Parameters are resolved once, now: a mistake is the caller's error, not a failed job,
  // and the worker runs what was resolved.
  absl::StatusOr<std::string> parameters = runtime::ResolveJobParameters(r->parameters(), in);
  if (!parameters.ok()) return ToGrpcStatus(parameters.status());

  v1::Job job;
  if (!r->bricks().empty()) {
    // Checked now; the worker that plans cuts the volume (and refuses what bricks cannot run).
    if (absl::Status st = runtime::CheckBrickRequest(r->bricks()); !st.ok()) {
      return ToGrpcStatus(st);
    }
    job.mutable_bricks()->set_size(r->bricks());
  }
  job.set_tenant(tenant);
  job.set_request_id(r->request_id());
  *job.mutable_input() = in;
  *job.mutable_parameters() = r->parameters();
  job.set_pipeline_version(SHEETMESH_VERSION);
  job.set_resolved_parameters(*parameters);
  absl::StatusOr<std::string> key = CacheKey(tenant, *r, resolved, *parameters);
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
    // Brick tasks are work the queue holds too: a job of thousands of bricks counts as such.
    absl::StatusOr<int64_t> queued = ctx_->jobs->CountInState(v1::QUEUED);
    if (!queued.ok()) return ToGrpcStatus(queued.status());
    absl::StatusOr<int64_t> tasks = ctx_->jobs->CountQueuedTasks();
    if (!tasks.ok()) return ToGrpcStatus(tasks.status());
    if (*queued + *tasks >= ctx_->limits.max_queued_jobs) {
      return ToGrpcStatus(absl::ResourceExhaustedError(absl::StrCat(
          "the queue holds ", *queued, " jobs and ", *tasks,
          " brick tasks, the server's limit (max_queued_jobs = ", ctx_->limits.max_queued_jobs,
          "); retry later")));
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
  std::string tenant;
  if (grpc::Status a = ctx_->tenants->Authenticate(*context, &tenant); !a.ok()) return a;
  absl::StatusOr<v1::Job> job = FreshJob(*ctx_, tenant, r->name());
  if (!job.ok()) return ToGrpcStatus(job.status());
  *response = *job;
  return grpc::Status::OK;
}

grpc::Status JobServiceImpl::ListJobs(grpc::ServerContext* context, const v1::ListJobsRequest* r,
                                      v1::ListJobsResponse* response) {
  std::string tenant;
  if (grpc::Status a = ctx_->tenants->Authenticate(*context, &tenant); !a.ok()) return a;
  if (r->page_size() < 0) {
    return ToGrpcStatus(
        absl::InvalidArgumentError(absl::StrCat("page_size ", r->page_size(), " is negative")));
  }
  const int size = r->page_size() == 0 ? 50 : std::min(r->page_size(), 1000);
  std::string next;
  absl::StatusOr<std::vector<v1::Job>> jobs =
      ctx_->jobs->List(tenant, r->state(), size, r->page_token(), &next);
  if (!jobs.ok()) return ToGrpcStatus(jobs.status());
  for (v1::Job& j : *jobs) {
    if (j.state() == v1::RUNNING) {
      if (auto p = ctx_->host->Progress(j.name())) *j.mutable_progress() = *p;
    }
    PresentSplit(&j, nullptr);
    *response->add_jobs() = std::move(j);
  }
  response->set_next_page_token(next);
  return grpc::Status::OK;
}

grpc::Status JobServiceImpl::CancelJob(grpc::ServerContext* context, const v1::CancelJobRequest* r,
                                       v1::Job* response) {
  std::string tenant;
  if (grpc::Status a = ctx_->tenants->Authenticate(*context, &tenant); !a.ok()) return a;
  if (absl::StatusOr<v1::Job> mine = FreshJob(*ctx_, tenant, r->name()); !mine.ok()) {
    return ToGrpcStatus(mine.status());
  }
  absl::StatusOr<v1::Job> job = ctx_->jobs->RequestCancel(r->name());
  if (!job.ok()) return ToGrpcStatus(job.status());
  if (job->state() == v1::RUNNING) ctx_->host->MarkCancelled(job->name());
  // A split job's bricks stop with it.
  if (IsSplit(*job)) {
    if (absl::Status st = CancelTasks(*ctx_->jobs, *job); !st.ok()) return ToGrpcStatus(st);
    for (const std::string& task : job->bricks().tasks()) {
      ctx_->host->MarkCancelled(task);
      ctx_->events->Notify(task);
    }
  }
  ctx_->events->Notify(job->name());
  absl::StatusOr<v1::Job> fresh = FreshJob(*ctx_, tenant, r->name());
  *response = fresh.ok() ? *fresh : *job;
  return grpc::Status::OK;
}

grpc::Status JobServiceImpl::DeleteJob(grpc::ServerContext* context, const v1::DeleteJobRequest* r,
                                       v1::DeleteJobResponse*) {
  std::string tenant;
  if (grpc::Status a = ctx_->tenants->Authenticate(*context, &tenant); !a.ok()) return a;
  absl::StatusOr<v1::Job> mine = FreshJob(*ctx_, tenant, r->name());
  if (!mine.ok()) return ToGrpcStatus(mine.status());
  if (!mine->bricks().parent().empty()) {
    return ToGrpcStatus(absl::FailedPreconditionError(
        absl::StrCat(r->name(), " is brick ", mine->bricks().index(), " of ",
                     mine->bricks().parent(), ": it goes when that job is deleted")));
  }
  absl::Status st = ctx_->jobs->Delete(r->name());
  if (st.ok()) ctx_->events->Notify(r->name());
  return ToGrpcStatus(st);
}

}  // namespace sheetmesh::server
