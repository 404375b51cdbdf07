// The SQLite JobStore: one connection behind a mutex, WAL journal, synchronous=FULL so
// that an accepted job survives a crash. Tables: jobs (the Job message, with the columns
// queries need), job_blobs (the blobs each job names: input and artifacts), blob_owners
// (who uploaded what).
#include <sqlite3.h>

#include <mutex>
#include <optional>
#include <set>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/random.h"
#include "common/status_macros.h"
#include "server/job_store.h"
#include "server/job_store_rows.h"
#include "server/sqlite_job_schema.h"
#include "server/sqlite_util.h"

namespace sheetmesh::server {
namespace {

int64_t NowMs() { return absl::ToUnixMillis(absl::Now()); }

class SqliteJobStore : public JobStore {
 public:
  explicit SqliteJobStore(sqlite3* db)
      : db_(db), rng_(static_cast<uint64_t>(absl::GetCurrentTimeNanos())) {}
  ~SqliteJobStore() override { sqlite3_close(db_); }

  // The tables, made or brought up to date (sqlite_job_schema.h).
  absl::Status Init() { return InitSqliteJobSchema(db_); }

  absl::StatusOr<v1::Job> Create(v1::Job job, const std::string& cache_key,
                                 bool* created) override {
    std::lock_guard<std::mutex> lock(mu_);
    *created = false;
    if (job.tenant().empty()) job.set_tenant(kDefaultTenant);
    const std::string scoped = ScopedRequestId(job.tenant(), job.request_id());
    // Looked up under the write lock, so that another connection to the file cannot
    // create the same request in between.
    SM_RETURN_IF_ERROR(Exec("BEGIN IMMEDIATE"));
    std::optional<absl::StatusOr<v1::Job>> found;
    {
      Stmt q(db_, "SELECT job FROM jobs WHERE request_id = ?");
      if (absl::Status st = q.ok(); !st.ok()) found = st;
      q.Bind(1, scoped);
      if (!found && q.Step() == SQLITE_ROW) found = Parse(q.Blob(0));
    }
    if (found) {
      Exec("ROLLBACK").IgnoreError();
      return *found;
    }
    const int64_t seq = NextSeqLocked();
    const std::string id = NameNewJob(&job, seq, rng_.Next());
    if (absl::Status st = InsertJobLocked(id, seq, job, cache_key, ""); !st.ok()) {
      Exec("ROLLBACK").IgnoreError();
      return st;
    }
    SM_RETURN_IF_ERROR(Exec("COMMIT"));
    *created = true;
    return job;
  }

  absl::StatusOr<v1::Job> Get(const std::string& name) override {
    std::lock_guard<std::mutex> lock(mu_);
    return GetLocked(JobIdOf(name));
  }

  absl::StatusOr<std::optional<v1::Job>> FindByRequestId(const std::string& tenant,
                                                         const std::string& request_id) override {
    std::lock_guard<std::mutex> lock(mu_);
    Stmt q(db_, "SELECT job FROM jobs WHERE request_id = ?");
    SM_RETURN_IF_ERROR(q.ok());
    q.Bind(1, ScopedRequestId(tenant, request_id));
    if (q.Step() != SQLITE_ROW) return std::optional<v1::Job>();
    SM_ASSIGN_OR_RETURN(v1::Job j, Parse(q.Blob(0)));
    return std::optional<v1::Job>(std::move(j));
  }

  absl::StatusOr<std::vector<v1::Job>> List(const std::string& tenant, v1::JobState state,
                                            int page_size, const std::string& token,
                                            std::string* next) override {
    std::lock_guard<std::mutex> lock(mu_);
    int64_t before = INT64_MAX;
    if (!token.empty() && !absl::SimpleAtoi(token, &before)) {
      return absl::InvalidArgumentError(
          absl::StrCat("page_token '", token, "' is not one this server gave"));
    }
    Stmt q(db_, state == v1::JOB_STATE_UNSPECIFIED
                    ? "SELECT job, seq FROM jobs WHERE tenant = ? AND seq < ? "
                      "AND parent IS NULL ORDER BY seq DESC LIMIT ?"
                    : "SELECT job, seq FROM jobs WHERE tenant = ? AND seq < ? AND state = ? "
                      "AND parent IS NULL ORDER BY seq DESC LIMIT ?");
    SM_RETURN_IF_ERROR(q.ok());
    q.Bind(1, tenant.empty() ? std::string(kDefaultTenant) : tenant).Bind(2, before);
    if (state == v1::JOB_STATE_UNSPECIFIED) {
      q.Bind(3, int64_t{page_size} + 1);
    } else {
      q.Bind(3, int64_t{state}).Bind(4, int64_t{page_size} + 1);
    }
    std::vector<v1::Job> out;
    int64_t last = 0;
    next->clear();
    while (q.Step() == SQLITE_ROW) {
      if (static_cast<int>(out.size()) == page_size) {
        *next = absl::StrCat(last);
        break;
      }
      SM_ASSIGN_OR_RETURN(v1::Job j, Parse(q.Blob(0)));
      last = q.Int(1);
      out.push_back(std::move(j));
    }
    return out;
  }

  absl::StatusOr<std::optional<v1::Job>> LeaseNext(const std::string& worker,
                                                   absl::Duration lease) override {
    std::lock_guard<std::mutex> lock(mu_);
    SM_RETURN_IF_ERROR(Exec("BEGIN IMMEDIATE"));
    std::optional<v1::Job> out;
    absl::Status st = [&]() -> absl::Status {
      // A split job waits while one of its tasks is QUEUED or RUNNING.
      Stmt q(db_,
             "SELECT id, job FROM jobs j WHERE state = ?1 AND NOT EXISTS (SELECT 1 FROM jobs t "
             "WHERE t.parent = j.id AND t.state IN (?1, ?2)) ORDER BY seq LIMIT 1");
      SM_RETURN_IF_ERROR(q.ok());
      q.Bind(1, int64_t{v1::QUEUED}).Bind(2, int64_t{v1::RUNNING});
      if (q.Step() != SQLITE_ROW) return absl::OkStatus();
      const std::string id = q.Text(0);
      SM_ASSIGN_OR_RETURN(v1::Job job, Parse(q.Blob(1)));
      job.set_state(v1::RUNNING);
      job.set_attempts(job.attempts() + 1);
      *job.mutable_start_time() = NowTimestamp();
      Stmt u(db_,
             "UPDATE jobs SET state = ?, lease_owner = ?, lease_expires = ?, job = ? WHERE id = ?");
      SM_RETURN_IF_ERROR(u.ok());
      u.Bind(1, int64_t{v1::RUNNING})
          .Bind(2, worker)
          .Bind(3, NowMs() + absl::ToInt64Milliseconds(lease))
          .BindBlob(4, job.SerializeAsString())
          .Bind(5, id);
      SM_RETURN_IF_ERROR(u.Run());
      out = std::move(job);
      return absl::OkStatus();
    }();
    if (!st.ok()) {
      Exec("ROLLBACK").IgnoreError();
      return st;
    }
    SM_RETURN_IF_ERROR(Exec("COMMIT"));
    return out;
  }

  absl::Status Renew(const std::string& name, const std::string& worker,
                     absl::Duration lease) override {
    std::lock_guard<std::mutex> lock(mu_);
    Stmt u(db_, "UPDATE jobs SET lease_expires = ? WHERE id = ? AND state = ? AND lease_owner = ?");
    SM_RETURN_IF_ERROR(u.ok());
    u.Bind(1, NowMs() + absl::ToInt64Milliseconds(lease))
        .Bind(2, JobIdOf(name))
        .Bind(3, int64_t{v1::RUNNING})
        .Bind(4, worker);
    SM_RETURN_IF_ERROR(u.Run());
    if (sqlite3_changes(db_) != 1) {
      return absl::FailedPreconditionError(absl::StrCat(name, " is not running under ", worker));
    }
    return absl::OkStatus();
  }

  absl::Status SetProgress(const std::string& name, const std::string& worker,
                           const v1::JobProgress& p) override {
    std::lock_guard<std::mutex> lock(mu_);
    SM_ASSIGN_OR_RETURN(Row row, RowLocked(JobIdOf(name)));
    if (row.job.state() != v1::RUNNING || row.owner != worker) {
      return absl::FailedPreconditionError(absl::StrCat(name, " is not running under ", worker));
    }
    *row.job.mutable_progress() = p;
    return WriteJobLocked(JobIdOf(name), row.job);
  }

  absl::StatusOr<v1::Job> Finish(const std::string& name, const std::string& worker,
                                 v1::JobState state, const v1::JobError& error,
                                 const std::vector<v1::Artifact>& artifacts) override {
    std::lock_guard<std::mutex> lock(mu_);
    SM_ASSIGN_OR_RETURN(Row row, RowLocked(JobIdOf(name)));
    if (row.job.state() != v1::RUNNING || row.owner != worker) {
      return absl::FailedPreconditionError(absl::StrCat(name, " is not running under ", worker));
    }
    v1::Job& job = row.job;
    ApplyFinish(&job, state, error, artifacts);
    Stmt u(db_,
           "UPDATE jobs SET state = ?, lease_owner = NULL, lease_expires = NULL, job = ? WHERE id "
           "= ?");
    SM_RETURN_IF_ERROR(u.ok());
    u.Bind(1, int64_t{state}).BindBlob(2, job.SerializeAsString()).Bind(3, JobIdOf(name));
    SM_RETURN_IF_ERROR(Exec("BEGIN IMMEDIATE"));
    absl::Status st = u.Run();
    if (st.ok()) st = AddJobBlobsLocked(JobIdOf(name), job);
    if (st.ok() && MergedSplitJob(job)) st = DropTaskOutputsLocked(JobIdOf(name));
    if (!st.ok()) {
      Exec("ROLLBACK").IgnoreError();
      return st;
    }
    SM_RETURN_IF_ERROR(Exec("COMMIT"));
    return job;
  }

  absl::Status Release(const std::string& name, const std::string& worker) override {
    std::lock_guard<std::mutex> lock(mu_);
    SM_ASSIGN_OR_RETURN(Row row, RowLocked(JobIdOf(name)));
    if (row.job.state() != v1::RUNNING || row.owner != worker) return absl::OkStatus();
    row.job.set_state(v1::QUEUED);
    row.job.set_attempts(std::max(0, row.job.attempts() - 1));
    row.job.clear_progress();
    return SetStateLocked(JobIdOf(name), row.job);
  }

  absl::StatusOr<v1::Job> Split(const std::string& name, const std::string& worker,
                                const v1::Artifact& plan, int count) override {
    std::lock_guard<std::mutex> lock(mu_);
    const std::string id = JobIdOf(name);
    SM_RETURN_IF_ERROR(Exec("BEGIN IMMEDIATE"));
    absl::StatusOr<v1::Job> out = [&]() -> absl::StatusOr<v1::Job> {
      SM_ASSIGN_OR_RETURN(Row row, RowLocked(id));
      if (row.job.state() != v1::RUNNING || row.owner != worker) {
        return absl::FailedPreconditionError(absl::StrCat(name, " is not running under ", worker));
      }
      SM_RETURN_IF_ERROR(CheckSplittable(row.job, count));
      std::vector<v1::Job> tasks = BrickTasks(row.job, plan, count);
      int64_t seq = NextSeqLocked();
      std::vector<std::string> names;
      for (v1::Job& task : tasks) {
        const std::string task_id = NameNewJob(&task, seq, rng_.Next());
        SM_RETURN_IF_ERROR(InsertJobLocked(task_id, seq++, task, "", id));
        names.push_back(task.name());
      }
      ApplySplit(&row.job, plan, names);
      SM_RETURN_IF_ERROR(SetStateLocked(id, row.job));
      SM_RETURN_IF_ERROR(AddJobBlobsLocked(id, row.job));
      return row.job;
    }();
    if (!out.ok()) {
      Exec("ROLLBACK").IgnoreError();
      return out;
    }
    SM_RETURN_IF_ERROR(Exec("COMMIT"));
    return out;
  }

  absl::StatusOr<std::vector<v1::Job>> Tasks(const std::string& name) override {
    std::lock_guard<std::mutex> lock(mu_);
    SM_RETURN_IF_ERROR(RowLocked(JobIdOf(name)).status());
    Stmt q(db_, "SELECT job FROM jobs WHERE parent = ? ORDER BY seq");
    SM_RETURN_IF_ERROR(q.ok());
    q.Bind(1, JobIdOf(name));
    std::vector<v1::Job> out;
    while (q.Step() == SQLITE_ROW) {
      SM_ASSIGN_OR_RETURN(v1::Job j, Parse(q.Blob(0)));
      out.push_back(std::move(j));
    }
    return out;
  }

  absl::StatusOr<v1::Job> RequestCancel(const std::string& name) override {
    std::lock_guard<std::mutex> lock(mu_);
    SM_ASSIGN_OR_RETURN(Row row, RowLocked(JobIdOf(name)));
    v1::Job& job = row.job;
    if (job.state() == v1::QUEUED) {
      ApplyCancelBeforeStart(&job);
      SM_RETURN_IF_ERROR(SetStateLocked(JobIdOf(name), job));
    } else if (job.state() == v1::RUNNING) {
      Stmt u(db_, "UPDATE jobs SET cancel_requested = 1 WHERE id = ?");
      SM_RETURN_IF_ERROR(u.ok());
      u.Bind(1, JobIdOf(name));
      SM_RETURN_IF_ERROR(u.Run());
    }
    return job;
  }

  absl::StatusOr<int> CancelTasks(const std::string& name) override {
    std::lock_guard<std::mutex> lock(mu_);
    const std::string id = JobIdOf(name);
    SM_RETURN_IF_ERROR(Exec("BEGIN IMMEDIATE"));
    absl::StatusOr<int> out = [&]() -> absl::StatusOr<int> {
      std::vector<std::pair<std::string, v1::Job>> queued;
      {
        Stmt q(db_, "SELECT id, job FROM jobs WHERE parent = ? AND state = ?");
        SM_RETURN_IF_ERROR(q.ok());
        q.Bind(1, id).Bind(2, int64_t{v1::QUEUED});
        while (q.Step() == SQLITE_ROW) {
          SM_ASSIGN_OR_RETURN(v1::Job job, ParseStoredJob(q.Blob(1)));
          queued.emplace_back(q.Text(0), std::move(job));
        }
      }
      for (auto& [task_id, job] : queued) {
        ApplyCancelBeforeStart(&job);
        SM_RETURN_IF_ERROR(SetStateLocked(task_id, job));
      }
      Stmt u(db_, "UPDATE jobs SET cancel_requested = 1 WHERE parent = ? AND state = ?");
      SM_RETURN_IF_ERROR(u.ok());
      u.Bind(1, id).Bind(2, int64_t{v1::RUNNING});
      SM_RETURN_IF_ERROR(u.Run());
      return static_cast<int>(queued.size() + sqlite3_changes(db_));
    }();
    if (!out.ok()) {
      Exec("ROLLBACK").IgnoreError();
      return out;
    }
    SM_RETURN_IF_ERROR(Exec("COMMIT"));
    return out;
  }

  absl::StatusOr<bool> CancelRequested(const std::string& name) override {
    std::lock_guard<std::mutex> lock(mu_);
    Stmt q(db_, "SELECT cancel_requested, state FROM jobs WHERE id = ?");
    SM_RETURN_IF_ERROR(q.ok());
    q.Bind(1, JobIdOf(name));
    if (q.Step() != SQLITE_ROW) return absl::NotFoundError(absl::StrCat(name, " does not exist"));
    return q.Int(0) != 0 || q.Int(1) != v1::RUNNING;
  }

  absl::Status Delete(const std::string& name) override {
    std::lock_guard<std::mutex> lock(mu_);
    SM_ASSIGN_OR_RETURN(Row row, RowLocked(JobIdOf(name)));
    if (row.job.state() == v1::QUEUED || row.job.state() == v1::RUNNING) {
      return absl::FailedPreconditionError(absl::StrCat(
          name, " is ", v1::JobState_Name(row.job.state()), "; cancel it before deleting it"));
    }
    SM_RETURN_IF_ERROR(Exec("BEGIN IMMEDIATE"));
    absl::Status st = [&]() -> absl::Status {
      // The tasks of a split job first, with it.
      for (const char* sql :
           {"DELETE FROM job_blobs WHERE job_id IN (SELECT id FROM jobs WHERE parent = ?1)",
            "DELETE FROM jobs WHERE parent = ?1", "DELETE FROM jobs WHERE id = ?1",
            "DELETE FROM job_blobs WHERE job_id = ?1"}) {
        Stmt d(db_, sql);
        SM_RETURN_IF_ERROR(d.ok());
        d.Bind(1, JobIdOf(name));
        SM_RETURN_IF_ERROR(d.Run());
      }
      return absl::OkStatus();
    }();
    if (!st.ok()) {
      Exec("ROLLBACK").IgnoreError();
      return st;
    }
    return Exec("COMMIT");
  }

  absl::StatusOr<int> RequeueExpired(int max_attempts, bool all, bool not_the_jobs_fault,
                                     std::vector<v1::Job>* ended) override {
    std::lock_guard<std::mutex> lock(mu_);
    std::vector<std::pair<std::string, v1::Job>> expired;
    {
      Stmt q(db_, all ? "SELECT id, job FROM jobs WHERE state = ?"
                      : "SELECT id, job FROM jobs WHERE state = ? AND lease_expires < ?");
      SM_RETURN_IF_ERROR(q.ok());
      q.Bind(1, int64_t{v1::RUNNING});
      if (!all) q.Bind(2, NowMs());
      while (q.Step() == SQLITE_ROW) {
        SM_ASSIGN_OR_RETURN(v1::Job j, Parse(q.Blob(1)));
        expired.emplace_back(q.Text(0), std::move(j));
      }
    }
    for (auto& [id, job] : expired) {
      bool cancel = false;
      {
        Stmt q(db_, "SELECT cancel_requested FROM jobs WHERE id = ?");
        q.Bind(1, id);
        if (q.Step() == SQLITE_ROW) cancel = q.Int(0) != 0;
      }
      ApplyLostWorker(&job, cancel, max_attempts, not_the_jobs_fault);
      SM_RETURN_IF_ERROR(SetStateLocked(id, job));
      if (ended != nullptr && job.state() != v1::QUEUED) ended->push_back(job);
    }
    return static_cast<int>(expired.size());
  }

  absl::StatusOr<std::optional<v1::Job>> FindCached(const std::string& key) override {
    std::lock_guard<std::mutex> lock(mu_);
    Stmt q(db_, "SELECT job FROM jobs WHERE cache_key = ? AND state = ? ORDER BY seq LIMIT 1");
    SM_RETURN_IF_ERROR(q.ok());
    q.Bind(1, key).Bind(2, int64_t{v1::SUCCEEDED});
    if (q.Step() != SQLITE_ROW) return std::optional<v1::Job>();
    SM_ASSIGN_OR_RETURN(v1::Job j, Parse(q.Blob(0)));
    return std::optional<v1::Job>(std::move(j));
  }

  absl::StatusOr<int64_t> CountInState(v1::JobState state) override {
    std::lock_guard<std::mutex> lock(mu_);
    Stmt q(db_, "SELECT COUNT(*) FROM jobs WHERE state = ? AND parent IS NULL");
    SM_RETURN_IF_ERROR(q.ok());
    q.Bind(1, int64_t{state});
    return q.Step() == SQLITE_ROW ? q.Int(0) : 0;
  }

  absl::StatusOr<int64_t> CountQueuedTasks() override {
    std::lock_guard<std::mutex> lock(mu_);
    Stmt q(db_, "SELECT COUNT(*) FROM jobs WHERE state = ? AND parent IS NOT NULL");
    SM_RETURN_IF_ERROR(q.ok());
    q.Bind(1, int64_t{v1::QUEUED});
    return q.Step() == SQLITE_ROW ? q.Int(0) : 0;
  }

  absl::Status AddUploadedBlob(const std::string& tenant, const std::string& hash) override {
    std::lock_guard<std::mutex> lock(mu_);
    Stmt q(db_, "INSERT OR IGNORE INTO blob_owners (tenant, hash) VALUES (?, ?)");
    SM_RETURN_IF_ERROR(q.ok());
    q.Bind(1, tenant).Bind(2, hash);
    return q.Run();
  }

  absl::StatusOr<bool> OwnsBlob(const std::string& tenant, const std::string& hash) override {
    std::lock_guard<std::mutex> lock(mu_);
    Stmt q(db_,
           "SELECT 1 FROM blob_owners WHERE tenant = ?1 AND hash = ?2 UNION ALL "
           "SELECT 1 FROM job_blobs b JOIN jobs j ON j.id = b.job_id "
           "WHERE b.hash = ?2 AND j.tenant = ?1 LIMIT 1");
    SM_RETURN_IF_ERROR(q.ok());
    q.Bind(1, tenant).Bind(2, hash);
    return q.Step() == SQLITE_ROW;
  }

  absl::StatusOr<std::set<std::string>> ReferencedBlobs() override {
    std::lock_guard<std::mutex> lock(mu_);
    Stmt q(db_, "SELECT DISTINCT hash FROM job_blobs");
    SM_RETURN_IF_ERROR(q.ok());
    std::set<std::string> out;
    while (q.Step() == SQLITE_ROW) out.insert(q.Text(0));
    return out;
  }

  absl::Status ForgetBlob(const std::string& hash) override {
    std::lock_guard<std::mutex> lock(mu_);
    Stmt q(db_, "DELETE FROM blob_owners WHERE hash = ?");
    SM_RETURN_IF_ERROR(q.ok());
    q.Bind(1, hash);
    return q.Run();
  }

 private:
  struct Row {
    v1::Job job;
    std::string owner;
  };

  absl::Status Exec(const char* sql) { return server::Exec(db_, sql); }

  // The next job's sequence number (under the write lock).
  int64_t NextSeqLocked() {
    Stmt q(db_, "SELECT COALESCE(MAX(seq), 0) + 1 FROM jobs");
    return q.Step() == SQLITE_ROW ? q.Int(0) : 1;
  }

  // Inserts `job` as row `id`, with the blobs it names; a brick task names its job's row
  // in `parent` (empty: none, the column stays NULL, as `cache_key` without a key).
  absl::Status InsertJobLocked(const std::string& id, int64_t seq, const v1::Job& job,
                               const std::string& cache_key, const std::string& parent) {
    Stmt ins(db_,
             "INSERT INTO jobs (id, seq, request_id, state, cache_key, job, tenant, parent) "
             "VALUES (?, ?, ?, ?, ?, ?, ?, ?)");
    SM_RETURN_IF_ERROR(ins.ok());
    ins.Bind(1, id)
        .Bind(2, seq)
        .Bind(3, ScopedRequestId(job.tenant(), job.request_id()))
        .Bind(4, int64_t{job.state()})
        .BindBlob(6, job.SerializeAsString())
        .Bind(7, job.tenant());
    if (!cache_key.empty()) ins.Bind(5, cache_key);  // unbound parameters are NULL
    if (!parent.empty()) ins.Bind(8, parent);
    SM_RETURN_IF_ERROR(ins.Run());
    return AddJobBlobsLocked(id, job);
  }

  absl::Status AddJobBlobsLocked(const std::string& id, const v1::Job& job) {
    return AddSqliteJobBlobs(db_, id, job);
  }

  static absl::StatusOr<v1::Job> Parse(const std::string& blob) { return ParseStoredJob(blob); }

  // The tasks of the merged job `id` drop their outputs (their input and plan are the job's).
  absl::Status DropTaskOutputsLocked(const std::string& id) {
    std::vector<std::pair<std::string, v1::Job>> tasks;
    {
      Stmt q(db_, "SELECT id, job FROM jobs WHERE parent = ?");
      SM_RETURN_IF_ERROR(q.ok());
      q.Bind(1, id);
      while (q.Step() == SQLITE_ROW) {
        SM_ASSIGN_OR_RETURN(v1::Job t, Parse(q.Blob(1)));
        tasks.emplace_back(q.Text(0), std::move(t));
      }
    }
    for (auto& [task_id, task] : tasks) {
      ApplyMerged(&task);
      SM_RETURN_IF_ERROR(WriteJobLocked(task_id, task));
    }
    Stmt d(db_, "DELETE FROM job_blobs WHERE job_id IN (SELECT id FROM jobs WHERE parent = ?)");
    SM_RETURN_IF_ERROR(d.ok());
    d.Bind(1, id);
    return d.Run();
  }

  absl::StatusOr<Row> RowLocked(const std::string& id) {
    Stmt q(db_, "SELECT job, lease_owner FROM jobs WHERE id = ?");
    SM_RETURN_IF_ERROR(q.ok());
    q.Bind(1, id);
    if (q.Step() != SQLITE_ROW)
      return absl::NotFoundError(absl::StrCat("jobs/", id, " does not exist"));
    SM_ASSIGN_OR_RETURN(v1::Job j, Parse(q.Blob(0)));
    return Row{std::move(j), q.Text(1)};
  }

  absl::StatusOr<v1::Job> GetLocked(const std::string& id) {
    SM_ASSIGN_OR_RETURN(Row row, RowLocked(id));
    return row.job;
  }

  absl::Status WriteJobLocked(const std::string& id, const v1::Job& job) {
    Stmt u(db_, "UPDATE jobs SET job = ? WHERE id = ?");
    SM_RETURN_IF_ERROR(u.ok());
    u.BindBlob(1, job.SerializeAsString()).Bind(2, id);
    return u.Run();
  }

  absl::Status SetStateLocked(const std::string& id, const v1::Job& job) {
    Stmt u(db_,
           "UPDATE jobs SET state = ?, lease_owner = NULL, lease_expires = NULL, job = ? WHERE id "
           "= ?");
    SM_RETURN_IF_ERROR(u.ok());
    u.Bind(1, int64_t{job.state()}).BindBlob(2, job.SerializeAsString()).Bind(3, id);
    return u.Run();
  }

  std::mutex mu_;
  sqlite3* db_;
  Rng rng_;
};

}  // namespace

absl::StatusOr<std::unique_ptr<JobStore>> OpenSqliteJobStore(const std::string& path) {
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(path.c_str(), &db,
                      SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX,
                      nullptr) != SQLITE_OK) {
    const std::string msg = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    return absl::InternalError(absl::StrCat(path, ": cannot open the job store: ", msg));
  }
  auto store = std::make_unique<SqliteJobStore>(db);
  SM_RETURN_IF_ERROR(store->Init());
  return std::unique_ptr<JobStore>(std::move(store));
}

}  // namespace sheetmesh::server
