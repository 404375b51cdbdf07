#include "worker/runtime/worker_pool.h"

#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <iostream>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "worker/runtime/job_runner.h"

namespace sheetmesh::runtime {

std::string UniqueWorkerName(const std::string& prefix) {
  char host[256] = "";
  ::gethostname(host, sizeof(host) - 1);
  return absl::StrCat(prefix, "-", host, "-", ::getpid(), "-",
                      absl::Hex(absl::GetCurrentTimeNanos() & 0xffffff));
}

// The host as the running job sees it: progress reports also answer "stop" when the pool
// aborts (draining past its timeout) or the lease was lost.
class PoolObserverHost : public JobHost {
 public:
  PoolObserverHost(WorkerPool* pool) : pool_(pool) {}
  absl::StatusOr<std::optional<v1::Job>> Lease(const std::string& w, absl::Duration d) override {
    return pool_->host_->Lease(w, d);
  }
  absl::Status Renew(const std::string& j, const std::string& w) override {
    return pool_->host_->Renew(j, w);
  }
  bool ReportProgress(const std::string& job, const std::string& worker,
                      const ProgressUpdate& u) override {
    if (pool_->aborting_.load()) return false;
    {
      std::lock_guard<std::mutex> lock(pool_->mu_);
      if (pool_->lost_[job] || pool_->cancelled_[job]) return false;
    }
    return pool_->host_->ReportProgress(job, worker, u);
  }
  absl::StatusOr<LocalVolume> ResolveInput(const v1::Job& job,
                                           const std::vector<ByteRange>* only) override {
    return pool_->host_->ResolveInput(job, only);
  }
  absl::StatusOr<v1::Artifact> PutArtifact(const std::string& job, const std::string& worker,
                                           const std::string& path,
                                           const std::string& media_type) override {
    return pool_->host_->PutArtifact(job, worker, path, media_type);
  }
  absl::Status Finish(const std::string& j, const std::string& w, const absl::Status& r,
                      const std::vector<v1::Artifact>& a) override {
    return pool_->host_->Finish(j, w, r, a);
  }
  absl::Status Release(const std::string& j, const std::string& w) override {
    return pool_->host_->Release(j, w);
  }
  absl::Status Split(const std::string& j, const std::string& w, const v1::Artifact& plan,
                     int count) override {
    return pool_->host_->Split(j, w, plan, count);
  }
  absl::Status FetchBlob(const v1::Digest& d, const std::string& path) override {
    return pool_->host_->FetchBlob(d, path);
  }

 private:
  WorkerPool* pool_;
};

WorkerPool::WorkerPool(JobHost* host, WorkerPoolOptions options)
    : host_(host), options_(std::move(options)) {
  if (options_.workers <= 0) {
    options_.workers = std::max(1u, std::thread::hardware_concurrency());
  }
}

WorkerPool::~WorkerPool() { Drain(absl::ZeroDuration()); }

void WorkerPool::Start() {
  for (int i = 0; i < options_.workers; ++i) threads_.emplace_back([this, i] { Work(i); });
  renewer_ = std::thread([this] { Renew(); });
}

void WorkerPool::Work(int index) {
  const std::string worker = absl::StrCat(options_.name, "-", index);
  PoolObserverHost host(this);
  while (leasing_.load()) {
    absl::StatusOr<std::optional<v1::Job>> leased = host_->Lease(worker, options_.lease_poll);
    if (!leased.ok()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      continue;
    }
    if (!leased->has_value()) continue;
    const v1::Job job = **leased;
    {
      std::lock_guard<std::mutex> lock(mu_);
      running_[job.name()] = worker;
      lost_[job.name()] = false;
      cancelled_[job.name()] = false;
    }
    ++busy_;
    const JobOutcome result = RunJob(job, worker, host, options_.run);
    bool lost, cancelled;
    {
      std::lock_guard<std::mutex> lock(mu_);
      lost = lost_[job.name()];
      cancelled = cancelled_[job.name()];
      running_.erase(job.name());
      lost_.erase(job.name());
      cancelled_.erase(job.name());
    }
    if (lost || result.split) {
      // Someone else owns the job now (or it was deleted), or it went back to the queue
      // split into its bricks: report nothing.
    } else if (aborting_.load() && !cancelled &&
               result.status.code() == absl::StatusCode::kCancelled) {
      host_->Release(job.name(), worker).IgnoreError();  // runs again after restart
    } else {
      // A refused finish leaves the job to its lease, which expires and runs it again: say
      // why, where the operator looks.
      const absl::Status finished =
          host_->Finish(job.name(), worker, result.status, result.artifacts);
      if (!finished.ok()) {
        std::cerr << "sheetmesh worker " << worker << ": " << job.name()
                  << " could not be finished: " << finished << std::endl;
        // Results the server refuses (not a server that is away) fail the job, saying why,
        // rather than running it again to the same refusal.
        if (result.status.ok() && finished.code() != absl::StatusCode::kUnavailable &&
            finished.code() != absl::StatusCode::kDeadlineExceeded) {
          host_
              ->Finish(job.name(), worker,
                       absl::InternalError(absl::StrCat("the server refused the job's results: ",
                                                        finished.message())),
                       {})
              .IgnoreError();
        }
      }
    }
    --busy_;
  }
}

void WorkerPool::Renew() {
  auto next = std::chrono::steady_clock::now();
  while (!threads_.empty() && (leasing_.load() || busy_.load() > 0)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    if (std::chrono::steady_clock::now() < next) continue;
    next = std::chrono::steady_clock::now() + absl::ToChronoMilliseconds(options_.renew_interval);
    std::map<std::string, std::string> running;
    {
      std::lock_guard<std::mutex> lock(mu_);
      running = running_;
    }
    for (const auto& [job, worker] : running) {
      const absl::Status renewed = host_->Renew(job, worker);
      if (renewed.ok()) continue;
      std::lock_guard<std::mutex> lock(mu_);
      // A cancel stops the job, which then ends CANCELLED (as when a progress report hears
      // of it first); only a lost lease reports nothing (once, that waited out the lease).
      (absl::IsCancelled(renewed) ? cancelled_ : lost_)[job] = true;
    }
  }
}

void WorkerPool::Drain(absl::Duration timeout) {
  leasing_.store(false);
  const auto deadline = std::chrono::steady_clock::now() + absl::ToChronoMilliseconds(timeout);
  while (busy_.load() > 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  aborting_.store(true);
  for (std::thread& t : threads_) {
    if (t.joinable()) t.join();
  }
  if (renewer_.joinable()) renewer_.join();
}

}  // namespace sheetmesh::runtime
