#include "server/memory_job_store.h"

#include <algorithm>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <utility>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/random.h"
#include "common/status_macros.h"
#include "server/job_store_rows.h"

namespace sheetmesh::server {

struct MemoryJobTables {
  struct Row {
    int64_t seq = 0;
    std::string request_key;  // ScopedRequestId
    std::string owner;        // lease owner while RUNNING
    absl::Time lease_expires = absl::InfinitePast();
    bool cancel_requested = false;
    std::string cache_key;
    v1::Job job;
  };
  std::mutex mu;
  std::map<std::string, Row> jobs;                         // by id
  std::set<std::pair<std::string, std::string>> uploaded;  // (tenant, hash)
  int64_t last_seq = 0;
};

std::shared_ptr<MemoryJobTables> NewMemoryJobTables() {
  return std::make_shared<MemoryJobTables>();
}

absl::Time ManualClock::Now() const {
  std::lock_guard<std::mutex> lock(mu_);
  return now_;
}

void ManualClock::Advance(absl::Duration d) {
  std::lock_guard<std::mutex> lock(mu_);
  now_ += d;
}

namespace {

using Row = MemoryJobTables::Row;

class MemoryJobStore : public JobStore {
 public:
  MemoryJobStore(std::shared_ptr<MemoryJobTables> tables, StoreClock clock)
      : t_(std::move(tables)),
        clock_(std::move(clock)),
        rng_(static_cast<uint64_t>(absl::GetCurrentTimeNanos())) {}

  absl::StatusOr<v1::Job> Create(v1::Job job, const std::string& cache_key,
                                 bool* created) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    *created = false;
    if (job.tenant().empty()) job.set_tenant(kDefaultTenant);
    const std::string key = ScopedRequestId(job.tenant(), job.request_id());
    for (const auto& [id, row] : t_->jobs) {
      if (row.request_key == key) return row.job;
    }
    Row row;
    row.seq = ++t_->last_seq;
    const std::string id = NameNewJob(&job, row.seq, rng_.Next(), clock_());
    row.request_key = key;
    row.cache_key = cache_key;
    row.job = job;
    t_->jobs.emplace(id, std::move(row));
    *created = true;
    return job;
  }

  absl::StatusOr<v1::Job> Get(const std::string& name) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    Row* row;
    SM_ASSIGN_OR_RETURN(row, RowLocked(name));
    return row->job;
  }

  absl::StatusOr<std::optional<v1::Job>> FindByRequestId(const std::string& tenant,
                                                         const std::string& request_id) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    const std::string key = ScopedRequestId(tenant, request_id);
    for (const auto& [id, row] : t_->jobs) {
      if (row.request_key == key) return std::optional<v1::Job>(row.job);
    }
    return std::optional<v1::Job>();
  }

  absl::StatusOr<std::vector<v1::Job>> List(const std::string& tenant, v1::JobState state,
                                            int page_size, const std::string& token,
                                            std::string* next) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    int64_t before = INT64_MAX;
    if (!token.empty() && !absl::SimpleAtoi(token, &before)) {
      return absl::InvalidArgumentError(
          absl::StrCat("page_token '", token, "' is not one this server gave"));
    }
    const std::string who = tenant.empty() ? std::string(kDefaultTenant) : tenant;
    std::vector<const Row*> rows;
    for (const auto& [id, row] : t_->jobs) {
      if (row.job.tenant() == who && row.seq < before && row.job.bricks().parent().empty() &&
          (state == v1::JOB_STATE_UNSPECIFIED || row.job.state() == state)) {
        rows.push_back(&row);
      }
    }
    std::sort(rows.begin(), rows.end(), [](const Row* a, const Row* b) { return a->seq > b->seq; });
    next->clear();
    std::vector<v1::Job> out;
    for (const Row* row : rows) {
      if (static_cast<int>(out.size()) == page_size) {
        *next = absl::StrCat(rows[out.size() - 1]->seq);
        break;
      }
      out.push_back(row->job);
    }
    return out;
  }

  absl::StatusOr<std::optional<v1::Job>> LeaseNext(const std::string& worker,
                                                   absl::Duration lease) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    Row* oldest = nullptr;
    for (auto& [id, row] : t_->jobs) {
      if (row.job.state() == v1::QUEUED && (oldest == nullptr || row.seq < oldest->seq) &&
          !WaitsLocked(row.job)) {
        oldest = &row;
      }
    }
    if (oldest == nullptr) return std::optional<v1::Job>();
    const absl::Time now = clock_();
    v1::Job& job = oldest->job;
    job.set_state(v1::RUNNING);
    job.set_attempts(job.attempts() + 1);
    *job.mutable_start_time() = TimestampOf(now);
    oldest->owner = worker;
    oldest->lease_expires = now + lease;
    return std::optional<v1::Job>(job);
  }

  absl::Status Renew(const std::string& name, const std::string& worker,
                     absl::Duration lease) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    Row* row;
    SM_ASSIGN_OR_RETURN(row, RunningLocked(name, worker));
    row->lease_expires = clock_() + lease;
    return absl::OkStatus();
  }

  absl::Status SetProgress(const std::string& name, const std::string& worker,
                           const v1::JobProgress& progress) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    Row* row;
    SM_ASSIGN_OR_RETURN(row, RunningLocked(name, worker));
    *row->job.mutable_progress() = progress;
    return absl::OkStatus();
  }

  absl::StatusOr<v1::Job> Finish(const std::string& name, const std::string& worker,
                                 v1::JobState state, const v1::JobError& error,
                                 const std::vector<v1::Artifact>& artifacts) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    Row* row;
    SM_ASSIGN_OR_RETURN(row, RunningLocked(name, worker));
    ApplyFinish(&row->job, state, error, artifacts, clock_());
    row->owner.clear();
    if (MergedSplitJob(row->job)) {
      for (const std::string& task : row->job.bricks().tasks()) {
        if (auto it = t_->jobs.find(JobIdOf(task)); it != t_->jobs.end()) {
          ApplyMerged(&it->second.job);
        }
      }
    }
    return row->job;
  }

  absl::Status Release(const std::string& name, const std::string& worker) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    Row* row;
    SM_ASSIGN_OR_RETURN(row, RowLocked(name));
    if (row->job.state() != v1::RUNNING || row->owner != worker) return absl::OkStatus();
    row->job.set_state(v1::QUEUED);
    row->job.set_attempts(std::max(0, row->job.attempts() - 1));
    row->job.clear_progress();
    row->owner.clear();
    return absl::OkStatus();
  }

  absl::StatusOr<v1::Job> Split(const std::string& name, const std::string& worker,
                                const v1::Artifact& plan, int count) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    Row* row;
    SM_ASSIGN_OR_RETURN(row, RunningLocked(name, worker));
    SM_RETURN_IF_ERROR(CheckSplittable(row->job, count));
    std::vector<v1::Job> tasks = BrickTasks(row->job, plan, count);
    std::vector<std::string> names;
    for (v1::Job& task : tasks) {
      Row r;
      r.seq = ++t_->last_seq;
      const std::string id = NameNewJob(&task, r.seq, rng_.Next(), clock_());
      r.request_key = ScopedRequestId(task.tenant(), task.request_id());
      r.job = std::move(task);
      names.push_back(r.job.name());
      t_->jobs.emplace(id, std::move(r));
    }
    ApplySplit(&row->job, plan, names);
    row->owner.clear();
    return row->job;
  }

  absl::StatusOr<std::vector<v1::Job>> Tasks(const std::string& name) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    Row* row;
    SM_ASSIGN_OR_RETURN(row, RowLocked(name));
    std::vector<v1::Job> out;
    for (const std::string& task : row->job.bricks().tasks()) {
      auto it = t_->jobs.find(JobIdOf(task));
      if (it != t_->jobs.end()) out.push_back(it->second.job);
    }
    return out;
  }

  absl::StatusOr<v1::Job> RequestCancel(const std::string& name) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    Row* row;
    SM_ASSIGN_OR_RETURN(row, RowLocked(name));
    if (row->job.state() == v1::QUEUED) {
      ApplyCancelBeforeStart(&row->job, clock_());
    } else if (row->job.state() == v1::RUNNING) {
      row->cancel_requested = true;
    }
    return row->job;
  }

  absl::StatusOr<int> CancelTasks(const std::string& name) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    int touched = 0;
    for (auto& [task_name, row] : t_->jobs) {
      if (row.job.bricks().parent() != name) continue;
      if (row.job.state() == v1::QUEUED) {
        ApplyCancelBeforeStart(&row.job, clock_());
        ++touched;
      } else if (row.job.state() == v1::RUNNING) {
        row.cancel_requested = true;
        ++touched;
      }
    }
    return touched;
  }

  absl::StatusOr<bool> CancelRequested(const std::string& name) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    Row* row;
    SM_ASSIGN_OR_RETURN(row, RowLocked(name));
    return row->cancel_requested || row->job.state() != v1::RUNNING;
  }

  absl::Status Delete(const std::string& name) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    Row* row;
    SM_ASSIGN_OR_RETURN(row, RowLocked(name));
    if (row->job.state() == v1::QUEUED || row->job.state() == v1::RUNNING) {
      return absl::FailedPreconditionError(absl::StrCat(
          name, " is ", v1::JobState_Name(row->job.state()), "; cancel it before deleting it"));
    }
    for (const std::string& task : row->job.bricks().tasks()) t_->jobs.erase(JobIdOf(task));
    t_->jobs.erase(JobIdOf(name));
    return absl::OkStatus();
  }

  absl::StatusOr<int> RequeueExpired(int max_attempts, bool all, bool not_the_jobs_fault,
                                     std::vector<v1::Job>* ended) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    const absl::Time now = clock_();
    int n = 0;
    for (auto& [id, row] : t_->jobs) {
      if (row.job.state() != v1::RUNNING || (!all && !(row.lease_expires < now))) continue;
      ApplyLostWorker(&row.job, row.cancel_requested, max_attempts, not_the_jobs_fault, now);
      row.owner.clear();
      if (ended != nullptr && row.job.state() != v1::QUEUED) ended->push_back(row.job);
      ++n;
    }
    return n;
  }

  absl::StatusOr<std::optional<v1::Job>> FindCached(const std::string& cache_key) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    const Row* first = nullptr;
    for (const auto& [id, row] : t_->jobs) {
      if (row.cache_key == cache_key && row.job.state() == v1::SUCCEEDED &&
          (first == nullptr || row.seq < first->seq)) {
        first = &row;
      }
    }
    return first ? std::optional<v1::Job>(first->job) : std::optional<v1::Job>();
  }

  absl::StatusOr<int64_t> CountInState(v1::JobState state) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    return std::count_if(t_->jobs.begin(), t_->jobs.end(), [&](const auto& j) {
      return j.second.job.state() == state && j.second.job.bricks().parent().empty();
    });
  }

  absl::StatusOr<int64_t> CountQueuedTasks() override {
    std::lock_guard<std::mutex> lock(t_->mu);
    return std::count_if(t_->jobs.begin(), t_->jobs.end(), [&](const auto& j) {
      return j.second.job.state() == v1::QUEUED && !j.second.job.bricks().parent().empty();
    });
  }

  absl::Status AddUploadedBlob(const std::string& tenant, const std::string& hash) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    t_->uploaded.emplace(tenant, hash);
    return absl::OkStatus();
  }

  absl::StatusOr<bool> OwnsBlob(const std::string& tenant, const std::string& hash) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    if (t_->uploaded.count({tenant, hash}) > 0) return true;
    for (const auto& [id, row] : t_->jobs) {
      if (row.job.tenant() == tenant && BlobsOf(row.job).count(hash) > 0) return true;
    }
    return false;
  }

  absl::StatusOr<std::set<std::string>> ReferencedBlobs() override {
    std::lock_guard<std::mutex> lock(t_->mu);
    std::set<std::string> out;
    for (const auto& [id, row] : t_->jobs) out.merge(BlobsOf(row.job));
    return out;
  }

  absl::Status ForgetBlob(const std::string& hash) override {
    std::lock_guard<std::mutex> lock(t_->mu);
    std::erase_if(t_->uploaded, [&](const auto& owner) { return owner.second == hash; });
    return absl::OkStatus();
  }

 private:
  // Whether `job` is split and waits for a task.
  bool WaitsLocked(const v1::Job& job) {
    for (const std::string& task : job.bricks().tasks()) {
      auto it = t_->jobs.find(JobIdOf(task));
      if (it != t_->jobs.end() && TaskPending(it->second.job.state())) return true;
    }
    return false;
  }
  // The row of job `name`; kNotFound naming it.
  absl::StatusOr<Row*> RowLocked(const std::string& name) {
    auto it = t_->jobs.find(JobIdOf(name));
    if (it == t_->jobs.end()) {
      return absl::NotFoundError(absl::StrCat("jobs/", JobIdOf(name), " does not exist"));
    }
    return &it->second;
  }
  // The row of job `name` RUNNING under `worker`; kFailedPrecondition otherwise.
  absl::StatusOr<Row*> RunningLocked(const std::string& name, const std::string& worker) {
    SM_ASSIGN_OR_RETURN(Row * row, RowLocked(name));
    if (row->job.state() != v1::RUNNING || row->owner != worker) {
      return absl::FailedPreconditionError(absl::StrCat(name, " is not running under ", worker));
    }
    return row;
  }

  std::shared_ptr<MemoryJobTables> t_;
  StoreClock clock_;
  Rng rng_;
};

}  // namespace

std::unique_ptr<JobStore> OpenMemoryJobStore(std::shared_ptr<MemoryJobTables> tables,
                                             StoreClock clock) {
  return std::make_unique<MemoryJobStore>(std::move(tables), std::move(clock));
}

}  // namespace sheetmesh::server
