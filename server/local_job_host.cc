#include "server/local_job_host.h"

#include <unistd.h>

#include <filesystem>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_replace.h"
#include "absl/time/clock.h"
#include "common/file_util.h"
#include "common/status_macros.h"
#include "google/protobuf/util/time_util.h"
#include "server/bricked_jobs.h"
#include "server/references.h"

namespace sheetmesh::server {

using google::protobuf::util::TimeUtil;

LocalJobHost::LocalJobHost(JobStore* store, BlobStore* blobs, JobEvents* events,
                           LocalJobHostOptions options)
    : store_(store), blobs_(blobs), events_(events), options_(std::move(options)) {}

void LocalJobHost::WakeWorkers() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    ++wake_;
  }
  work_.notify_all();
}

absl::StatusOr<std::optional<v1::Job>> LocalJobHost::Lease(const std::string& worker,
                                                           absl::Duration wait) {
  const absl::Time deadline = absl::Now() + wait;
  for (;;) {
    uint64_t seen;
    {
      std::lock_guard<std::mutex> lock(mu_);
      seen = wake_;
    }
    SM_ASSIGN_OR_RETURN(std::optional<v1::Job> job, store_->LeaseNext(worker, options_.lease));
    if (job.has_value()) {
      const std::string name = job->name();
      // A split job comes back for its merge, or ends here when a brick did not succeed.
      SM_ASSIGN_OR_RETURN(job, PrepareMerge(*store_, *std::move(job), worker));
      if (!job.has_value()) {
        events_->NotifyFinished(name);
        continue;
      }
      {
        std::lock_guard<std::mutex> lock(mu_);
        Live live;
        live.parent = job->bricks().parent();
        live_[job->name()] = std::move(live);
      }
      events_->Notify(job->name());
      return job;
    }
    const absl::Duration left = deadline - absl::Now();
    if (left <= absl::ZeroDuration()) return std::optional<v1::Job>();
    std::unique_lock<std::mutex> lock(mu_);
    work_.wait_for(lock, absl::ToChronoMilliseconds(left), [&] { return wake_ != seen; });
  }
}

absl::Status LocalJobHost::Renew(const std::string& job, const std::string& worker) {
  return store_->Renew(job, worker, options_.lease);
}

void LocalJobHost::MarkCancelled(const std::string& job) {
  std::lock_guard<std::mutex> lock(mu_);
  cancelled_.insert(job);
}

bool LocalJobHost::ReportProgress(const std::string& job, const std::string& worker,
                                  const runtime::ProgressUpdate& u) {
  const absl::Time now = absl::Now();
  bool notify = false, store = false, new_stage = false, check_cancel = false;
  v1::JobProgress snapshot;
  std::string parent;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (cancelled_.count(job)) return false;
    Live& live = live_[job];
    new_stage = live.progress.stage() != u.stage || live.progress.stage_index() != u.stage_index;
    live.progress.set_stage(u.stage);
    live.progress.set_stage_index(u.stage_index);
    live.progress.set_stage_count(u.stage_count);
    live.progress.set_fraction(u.fraction);
    if (!u.message.empty() || new_stage) live.progress.set_message(u.message);
    *live.progress.mutable_update_time() =
        TimeUtil::MillisecondsToTimestamp(absl::ToUnixMillis(now));
    // Watchers hear of every stage and of every percent, at most ten times a second.
    if (new_stage || (u.fraction - live.notified_fraction >= 0.01 &&
                      now - live.notified >= absl::Milliseconds(100))) {
      notify = true;
      live.notified = now;
      live.notified_fraction = u.fraction;
    }
    if (new_stage || now - live.stored >= options_.progress_store_interval) {
      store = true;
      live.stored = now;
    }
    if (now - live.cancel_checked >= options_.cancel_poll_interval) {
      check_cancel = true;
      live.cancel_checked = now;
    }
    snapshot = live.progress;
    parent = live.parent;
    // A stage's start is recorded before anyone can read it as the live progress (Progress
    // takes mu_), so a watcher that sees stage k has every stage before k in its log too.
    if (new_stage) events_->NotifyStage(job, snapshot);
  }
  if (store && !store_->SetProgress(job, worker, snapshot).ok()) return false;
  if (check_cancel) {
    absl::StatusOr<bool> stop = store_->CancelRequested(job);
    if (stop.ok() && *stop) {
      MarkCancelled(job);
      return false;
    }
  }
  if (!new_stage && notify) events_->Notify(job);
  if (notify && !parent.empty()) events_->Notify(parent);  // a brick: its job's watchers too
  return true;
}

std::optional<v1::JobProgress> LocalJobHost::Progress(const std::string& job) {
  std::lock_guard<std::mutex> lock(mu_);
  auto it = live_.find(job);
  if (it == live_.end()) return std::nullopt;
  return it->second.progress;
}

absl::StatusOr<runtime::LocalVolume> LocalJobHost::ResolveInput(
    const v1::Job& job, const std::vector<runtime::ByteRange>* /*only*/) {
  const v1::JobInput& in = job.input();
  runtime::LocalVolume v;
  if (in.has_volume_digest()) {
    SM_ASSIGN_OR_RETURN(const std::string blob, blobs_->PathOf(in.volume_digest()));
    // Readers tell formats by name: give the blob the client's file name through a link.
    const std::string name = runtime::InputFileName(in);
    const std::string dir = absl::StrCat(options_.scratch_dir, "/inputs/",
                                         absl::StrReplaceAll(job.name(), {{"/", "-"}}));
    SM_RETURN_IF_ERROR(MakeDirs(dir));
    v.path = dir + "/" + name;
    ::unlink(v.path.c_str());
    if (::symlink(blob.c_str(), v.path.c_str()) != 0) return ErrnoStatus(errno, v.path);
    v.display_name = in.file_name().empty() ? DigestString(in.volume_digest()) : in.file_name();
    return v;
  }
  if (in.has_volume_files()) {
    // Hard links (a copy across file systems): the job's sandbox reads beneath its folder,
    // and a symbolic link would lead out of it into the blob store.
    const std::string dir = absl::StrCat(options_.scratch_dir, "/inputs/",
                                         absl::StrReplaceAll(job.name(), {{"/", "-"}}), "/",
                                         runtime::InputFolderName(in));
    SM_ASSIGN_OR_RETURN(v.path,
                        runtime::LayOutVolumeFiles(
                            in.volume_files(), dir,
                            [&](const v1::Digest& d, const std::string& path) -> absl::Status {
                              SM_ASSIGN_OR_RETURN(const std::string blob, blobs_->PathOf(d));
                              ::unlink(path.c_str());
                              if (::link(blob.c_str(), path.c_str()) == 0) return absl::OkStatus();
                              std::error_code ec;
                              std::filesystem::copy_file(blob, path, ec);
                              return ec ? ErrnoStatus(ec.value(), path) : absl::OkStatus();
                            }));
    v.display_name = runtime::InputFolderName(in);
    // A detached header's data file must be one of the volume's own files.
    v.data_files = true;
    v.data_file_roots = {dir};
    return v;
  }
  if (!in.volume_path().empty()) {
    SM_ASSIGN_OR_RETURN(v.path, ResolveReference(in.volume_path(), options_.allowed_roots));
    v.display_name = in.volume_path();
    v.data_files = true;
    v.data_file_roots = options_.allowed_roots;
    return v;
  }
  return absl::InvalidArgumentError(absl::StrCat(job.name(), ": input names no volume"));
}

absl::StatusOr<v1::Artifact> LocalJobHost::PutArtifact(const std::string& job,
                                                       const std::string& /*worker*/,
                                                       const std::string& path,
                                                       const std::string& media_type) {
  SM_ASSIGN_OR_RETURN(v1::Digest d, blobs_->PutFile(path));
  v1::Artifact a;
  a.set_name(std::filesystem::path(path).filename().string());
  *a.mutable_digest() = d;
  a.set_media_type(media_type);
  return a;
}

absl::Status LocalJobHost::Finish(const std::string& job, const std::string& worker,
                                  const absl::Status& result,
                                  const std::vector<v1::Artifact>& artifacts) {
  absl::StatusOr<v1::Job> done =
      store_->Finish(job, worker, runtime::EndStateOf(result), runtime::ErrorOf(result), artifacts);
  {
    std::lock_guard<std::mutex> lock(mu_);
    live_.erase(job);
    cancelled_.erase(job);
  }
  RemoveInputs(job);
  events_->NotifyFinished(job);
  if (done.ok()) TaskEnded(*store_, *events_, *done);
  return done.status();
}

void LocalJobHost::RemoveInputs(const std::string& job) {
  std::error_code ec;
  std::filesystem::remove_all(
      absl::StrCat(options_.scratch_dir, "/inputs/", absl::StrReplaceAll(job, {{"/", "-"}})), ec);
}

absl::Status LocalJobHost::Split(const std::string& job, const std::string& worker,
                                 const v1::Artifact& plan, int count) {
  const absl::Status allowed = CheckSplit(*store_, options_.split, job, count);
  absl::StatusOr<v1::Job> split =
      allowed.ok() ? store_->Split(job, worker, plan, count) : absl::StatusOr<v1::Job>(allowed);
  {
    std::lock_guard<std::mutex> lock(mu_);
    live_.erase(job);
  }
  RemoveInputs(job);
  events_->Notify(job);
  WakeWorkers();  // the bricks are queued
  return split.status();
}

absl::Status LocalJobHost::FetchBlob(const v1::Digest& digest, const std::string& path) {
  SM_ASSIGN_OR_RETURN(const std::string blob, blobs_->PathOf(digest));
  // A copy, not a link: the job's child may write in the folder it lies in, and a stored
  // blob must stay what its digest says.
  std::error_code ec;
  std::filesystem::remove(path, ec);
  std::filesystem::copy_file(blob, path, ec);
  return ec ? ErrnoStatus(ec.value(), path) : absl::OkStatus();
}

absl::Status LocalJobHost::Release(const std::string& job, const std::string& worker) {
  absl::Status st = store_->Release(job, worker);
  {
    std::lock_guard<std::mutex> lock(mu_);
    live_.erase(job);
  }
  events_->Notify(job);
  WakeWorkers();
  return st;
}

}  // namespace sheetmesh::server
