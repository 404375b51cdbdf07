// The PostgreSQL JobStore, for several servers over one database: the same tables as the
// SQLite store; jobs leased with SELECT ... FOR UPDATE SKIP LOCKED (two replicas never
// lease one job), lease times on the database's clock (replicas' clocks may differ),
// request ids unique by constraint (two replicas creating one request get one job).
#include <memory>

#include "absl/strings/numbers.h"
#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/random.h"
#include "common/status_macros.h"
#include "server/job_store.h"
#include "server/job_store_rows.h"
#include "server/postgres_util.h"

namespace sheetmesh::server {
namespace {

using Conn = PgPool::Lease;

// Milliseconds since the epoch on the database's clock, as SQL.
constexpr const char* kDbNowMs = "(extract(epoch from clock_timestamp()) * 1000)::bigint";

PgParam J(const v1::Job& job) { return PgParam::Bytes(job.SerializeAsString()); }

class PostgresJobStore : public JobStore {
 public:
  explicit PostgresJobStore(std::unique_ptr<PgPool> pool)
      : pool_(std::move(pool)), rng_(static_cast<uint64_t>(absl::GetCurrentTimeNanos())) {}

  absl::Status Init() {
    // One replica creates the tables; the others wait on the lock and find them.
    return pool_->Transaction([](Conn& c) -> absl::Status {
      for (const char* sql : {
               "SELECT pg_advisory_xact_lock(7402211)",
               "CREATE SEQUENCE IF NOT EXISTS job_seq",
               "CREATE TABLE IF NOT EXISTS jobs ("
               "  id TEXT PRIMARY KEY, seq BIGINT NOT NULL, request_id TEXT UNIQUE NOT NULL,"
               "  state INTEGER NOT NULL, lease_owner TEXT, lease_expires BIGINT,"
               "  cancel_requested BOOLEAN NOT NULL DEFAULT FALSE, cache_key TEXT,"
               "  job BYTEA NOT NULL, tenant TEXT NOT NULL DEFAULT 'default')",
               "CREATE INDEX IF NOT EXISTS jobs_state_seq ON jobs(state, seq)",
               "CREATE INDEX IF NOT EXISTS jobs_cache ON jobs(cache_key, state)",
               "CREATE INDEX IF NOT EXISTS jobs_tenant_seq ON jobs(tenant, seq)",
               "CREATE TABLE IF NOT EXISTS blob_owners ("
               "  tenant TEXT NOT NULL, hash TEXT NOT NULL, PRIMARY KEY (tenant, hash))",
               "CREATE TABLE IF NOT EXISTS job_blobs ("
               "  job_id TEXT NOT NULL, hash TEXT NOT NULL, PRIMARY KEY (job_id, hash))",
               "CREATE INDEX IF NOT EXISTS job_blobs_hash ON job_blobs(hash)",
               // A brick task names its job (stores from before bricks get the column).
               "ALTER TABLE jobs ADD COLUMN IF NOT EXISTS parent TEXT",
               "CREATE INDEX IF NOT EXISTS jobs_parent ON jobs(parent, state)",
           }) {
        SM_RETURN_IF_ERROR(c->Exec(sql));
      }
      return absl::OkStatus();
    });
  }

  absl::StatusOr<v1::Job> Create(v1::Job job, const std::string& cache_key,
                                 bool* created) override {
    *created = false;
    if (job.tenant().empty()) job.set_tenant(kDefaultTenant);
    const std::string scoped = ScopedRequestId(job.tenant(), job.request_id());
    SM_ASSIGN_OR_RETURN(std::optional<v1::Job> existing, ByRequestId(scoped));
    if (existing) return *existing;
    v1::Job out;
    absl::Status st = pool_->Transaction([&](Conn& c) -> absl::Status {
      int64_t n = 0;
      SM_ASSIGN_OR_RETURN(const std::string id, NameNew(c, &job, &n));
      SM_ASSIGN_OR_RETURN(
          PgResult ins,
          c->Query("INSERT INTO jobs (id, seq, request_id, state, cache_key, job, tenant) "
                   "VALUES ($1, $2, $3, $4, $5, $6, $7) ON CONFLICT (request_id) DO NOTHING",
                   {P(id), P(n), P(scoped), P(int64_t{job.state()}), P(cache_key), J(job),
                    P(job.tenant())}));
      if (ins.affected() == 0) return absl::AlreadyExistsError("raced");
      SM_RETURN_IF_ERROR(AddJobBlobs(c, id, job));
      out = job;
      return absl::OkStatus();
    });
    if (absl::IsAlreadyExists(st)) {  // another replica created it first
      SM_ASSIGN_OR_RETURN(existing, ByRequestId(scoped));
      if (existing) return *existing;
    }
    SM_RETURN_IF_ERROR(st);
    *created = true;
    return out;
  }

  absl::StatusOr<v1::Job> Get(const std::string& name) override {
    SM_ASSIGN_OR_RETURN(Conn c, pool_->Get());
    SM_ASSIGN_OR_RETURN(Row row, RowOf(c, JobIdOf(name), false));
    return row.job;
  }

  absl::StatusOr<std::optional<v1::Job>> FindByRequestId(const std::string& tenant,
                                                         const std::string& request_id) override {
    return ByRequestId(ScopedRequestId(tenant, request_id));
  }

  absl::StatusOr<std::vector<v1::Job>> List(const std::string& tenant, v1::JobState state,
                                            int page_size, const std::string& token,
                                            std::string* next) override {
    int64_t before = INT64_MAX;
    if (!token.empty() && !absl::SimpleAtoi(token, &before)) {
      return absl::InvalidArgumentError(
          absl::StrCat("page_token '", token, "' is not one this server gave"));
    }
    SM_ASSIGN_OR_RETURN(Conn c, pool_->Get());
    const std::string t = tenant.empty() ? std::string(kDefaultTenant) : tenant;
    absl::StatusOr<PgResult> q =
        state == v1::JOB_STATE_UNSPECIFIED
            ? c->Query(
                  "SELECT job, seq FROM jobs WHERE tenant = $1 AND seq < $2 "
                  "AND parent IS NULL ORDER BY seq DESC LIMIT $3",
                  {P(t), P(before), P(int64_t{page_size} + 1)})
            : c->Query(
                  "SELECT job, seq FROM jobs WHERE tenant = $1 AND seq < $2 AND state = $3 "
                  "AND parent IS NULL ORDER BY seq DESC LIMIT $4",
                  {P(t), P(before), P(int64_t{state}), P(int64_t{page_size} + 1)});
    SM_RETURN_IF_ERROR(q.status());
    std::vector<v1::Job> out;
    next->clear();
    for (int i = 0; i < q->rows(); ++i) {
      if (static_cast<int>(out.size()) == page_size) {
        *next = absl::StrCat(q->Int(i - 1, 1));
        break;
      }
      SM_ASSIGN_OR_RETURN(v1::Job j, ParseStoredJob(q->Bytes(i, 0)));
      out.push_back(std::move(j));
    }
    return out;
  }

  absl::StatusOr<std::optional<v1::Job>> LeaseNext(const std::string& worker,
                                                   absl::Duration lease) override {
    std::optional<v1::Job> out;
    SM_RETURN_IF_ERROR(pool_->Transaction([&](Conn& c) -> absl::Status {
      // A split job waits while one of its tasks is QUEUED or RUNNING.
      SM_ASSIGN_OR_RETURN(
          PgResult q,
          c->Query("SELECT id, job FROM jobs j WHERE state = $1 AND NOT EXISTS (SELECT 1 FROM "
                   "jobs t WHERE t.parent = j.id AND t.state IN ($1, $2)) "
                   "ORDER BY seq LIMIT 1 FOR UPDATE OF j SKIP LOCKED",
                   {P(int64_t{v1::QUEUED}), P(int64_t{v1::RUNNING})}));
      if (q.rows() == 0) return absl::OkStatus();
      const std::string id = q.Text(0, 0);
      SM_ASSIGN_OR_RETURN(v1::Job job, ParseStoredJob(q.Bytes(0, 1)));
      job.set_state(v1::RUNNING);
      job.set_attempts(job.attempts() + 1);
      *job.mutable_start_time() = NowTimestamp();
      SM_RETURN_IF_ERROR(c->Query(absl::StrCat("UPDATE jobs SET state = $1, lease_owner = $2, "
                                               "lease_expires = ",
                                               kDbNowMs, " + $3, job = $4 WHERE id = $5"),
                                  {P(int64_t{v1::RUNNING}), P(worker),
                                   P(absl::ToInt64Milliseconds(lease)), J(job), P(id)})
                             .status());
      out = std::move(job);
      return absl::OkStatus();
    }));
    return out;
  }

  absl::Status Renew(const std::string& name, const std::string& worker,
                     absl::Duration lease) override {
    SM_ASSIGN_OR_RETURN(Conn c, pool_->Get());
    SM_ASSIGN_OR_RETURN(
        PgResult u,
        c->Query(absl::StrCat("UPDATE jobs SET lease_expires = ", kDbNowMs,
                              " + $1 WHERE id = $2 AND state = $3 AND lease_owner = $4"),
                 {P(absl::ToInt64Milliseconds(lease)), P(JobIdOf(name)), P(int64_t{v1::RUNNING}),
                  P(worker)}));
    if (u.affected() != 1) return NotRunningUnder(name, worker);
    return absl::OkStatus();
  }

  absl::Status SetProgress(const std::string& name, const std::string& worker,
                           const v1::JobProgress& p) override {
    return pool_->Transaction([&](Conn& c) -> absl::Status {
      SM_ASSIGN_OR_RETURN(Row row, RowOf(c, JobIdOf(name), true));
      if (row.job.state() != v1::RUNNING || row.owner != worker) {
        return NotRunningUnder(name, worker);
      }
      *row.job.mutable_progress() = p;
      return c->Query("UPDATE jobs SET job = $1 WHERE id = $2", {J(row.job), P(JobIdOf(name))})
          .status();
    });
  }

  absl::StatusOr<v1::Job> Finish(const std::string& name, const std::string& worker,
                                 v1::JobState state, const v1::JobError& error,
                                 const std::vector<v1::Artifact>& artifacts) override {
    v1::Job out;
    SM_RETURN_IF_ERROR(pool_->Transaction([&](Conn& c) -> absl::Status {
      SM_ASSIGN_OR_RETURN(Row row, RowOf(c, JobIdOf(name), true));
      if (row.job.state() != v1::RUNNING || row.owner != worker) {
        return NotRunningUnder(name, worker);
      }
      v1::Job& job = row.job;
      ApplyFinish(&job, state, error, artifacts);
      SM_RETURN_IF_ERROR(SetState(c, JobIdOf(name), job));
      SM_RETURN_IF_ERROR(AddJobBlobs(c, JobIdOf(name), job));
      if (MergedSplitJob(job)) SM_RETURN_IF_ERROR(DropTaskOutputs(c, JobIdOf(name)));
      out = job;
      return absl::OkStatus();
    }));
    return out;
  }

  absl::Status Release(const std::string& name, const std::string& worker) override {
    return pool_->Transaction([&](Conn& c) -> absl::Status {
      SM_ASSIGN_OR_RETURN(Row row, RowOf(c, JobIdOf(name), true));
      if (row.job.state() != v1::RUNNING || row.owner != worker) return absl::OkStatus();
      row.job.set_state(v1::QUEUED);
      row.job.set_attempts(std::max(0, row.job.attempts() - 1));
      row.job.clear_progress();
      return SetState(c, JobIdOf(name), row.job);
    });
  }

  absl::StatusOr<v1::Job> Split(const std::string& name, const std::string& worker,
                                const v1::Artifact& plan, int count) override {
    v1::Job out;
    SM_RETURN_IF_ERROR(pool_->Transaction([&](Conn& c) -> absl::Status {
      const std::string id = JobIdOf(name);
      SM_ASSIGN_OR_RETURN(Row row, RowOf(c, id, true));
      if (row.job.state() != v1::RUNNING || row.owner != worker) {
        return NotRunningUnder(name, worker);
      }
      SM_RETURN_IF_ERROR(CheckSplittable(row.job, count));
      std::vector<v1::Job> tasks = BrickTasks(row.job, plan, count);
      std::vector<std::string> names;
      for (v1::Job& task : tasks) {
        int64_t n = 0;
        SM_ASSIGN_OR_RETURN(const std::string task_id, NameNew(c, &task, &n));
        SM_RETURN_IF_ERROR(
            c->Query("INSERT INTO jobs (id, seq, request_id, state, job, tenant, parent) "
                     "VALUES ($1, $2, $3, $4, $5, $6, $7)",
                     {P(task_id), P(n), P(ScopedRequestId(task.tenant(), task.request_id())),
                      P(int64_t{v1::QUEUED}), J(task), P(task.tenant()), P(id)})
                .status());
        SM_RETURN_IF_ERROR(AddJobBlobs(c, task_id, task));
        names.push_back(task.name());
      }
      ApplySplit(&row.job, plan, names);
      SM_RETURN_IF_ERROR(SetState(c, id, row.job));
      SM_RETURN_IF_ERROR(AddJobBlobs(c, id, row.job));
      out = row.job;
      return absl::OkStatus();
    }));
    return out;
  }

  absl::StatusOr<std::vector<v1::Job>> Tasks(const std::string& name) override {
    SM_ASSIGN_OR_RETURN(Conn c, pool_->Get());
    SM_RETURN_IF_ERROR(RowOf(c, JobIdOf(name), false).status());
    SM_ASSIGN_OR_RETURN(PgResult q, c->Query("SELECT job FROM jobs WHERE parent = $1 ORDER BY seq",
                                             {P(JobIdOf(name))}));
    std::vector<v1::Job> out;
    for (int i = 0; i < q.rows(); ++i) {
      SM_ASSIGN_OR_RETURN(v1::Job j, ParseStoredJob(q.Bytes(i, 0)));
      out.push_back(std::move(j));
    }
    return out;
  }

  absl::StatusOr<v1::Job> RequestCancel(const std::string& name) override {
    v1::Job out;
    SM_RETURN_IF_ERROR(pool_->Transaction([&](Conn& c) -> absl::Status {
      SM_ASSIGN_OR_RETURN(Row row, RowOf(c, JobIdOf(name), true));
      v1::Job& job = row.job;
      if (job.state() == v1::QUEUED) {
        ApplyCancelBeforeStart(&job);
        SM_RETURN_IF_ERROR(SetState(c, JobIdOf(name), job));
      } else if (job.state() == v1::RUNNING) {
        SM_RETURN_IF_ERROR(
            c->Query("UPDATE jobs SET cancel_requested = TRUE WHERE id = $1", {P(JobIdOf(name))})
                .status());
      }
      out = job;
      return absl::OkStatus();
    }));
    return out;
  }

  absl::StatusOr<int> CancelTasks(const std::string& name) override {
    int touched = 0;
    SM_RETURN_IF_ERROR(pool_->Transaction([&](Conn& c) -> absl::Status {
      const std::string id = JobIdOf(name);
      SM_ASSIGN_OR_RETURN(
          PgResult q, c->Query("SELECT id, job FROM jobs WHERE parent = $1 AND state = $2 "
                               "FOR UPDATE",
                               {P(id), P(int64_t{v1::QUEUED})}));
      // Every cancelled task in one statement (arrays of ids and protos): a round trip per
      // task made a job of thousands of bricks take most of a minute to cancel.
      std::string ids = "{", jobs = "{";
      for (int i = 0; i < q.rows(); ++i) {
        SM_ASSIGN_OR_RETURN(v1::Job job, ParseStoredJob(q.Bytes(i, 1)));
        ApplyCancelBeforeStart(&job);
        absl::StrAppend(&ids, i ? "," : "", "\"", q.Text(i, 0), "\"");
        absl::StrAppend(&jobs, i ? "," : "", "\"\\\\x", absl::BytesToHexString(job.SerializeAsString()),
                        "\"");
      }
      ids += "}";
      jobs += "}";
      if (q.rows() > 0) {
        SM_RETURN_IF_ERROR(
            c->Query("UPDATE jobs SET state = $1, lease_owner = NULL, lease_expires = NULL, "
                     "job = v.job FROM (SELECT unnest($2::text[]) AS id, unnest($3::bytea[]) "
                     "AS job) AS v WHERE jobs.id = v.id",
                     {P(int64_t{v1::CANCELLED}), P(ids), P(jobs)})
                .status());
      }
      SM_ASSIGN_OR_RETURN(
          PgResult u, c->Query("UPDATE jobs SET cancel_requested = TRUE WHERE parent = $1 AND "
                               "state = $2",
                               {P(id), P(int64_t{v1::RUNNING})}));
      touched = q.rows() + static_cast<int>(u.affected());
      return absl::OkStatus();
    }));
    return touched;
  }

  absl::StatusOr<bool> CancelRequested(const std::string& name) override {
    SM_ASSIGN_OR_RETURN(Conn c, pool_->Get());
    SM_ASSIGN_OR_RETURN(
        PgResult q,
        c->Query("SELECT cancel_requested, state FROM jobs WHERE id = $1", {P(JobIdOf(name))}));
    if (q.rows() == 0) return absl::NotFoundError(absl::StrCat(name, " does not exist"));
    return q.Text(0, 0) == "t" || q.Int(0, 1) != v1::RUNNING;
  }

  absl::Status Delete(const std::string& name) override {
    return pool_->Transaction([&](Conn& c) -> absl::Status {
      SM_ASSIGN_OR_RETURN(Row row, RowOf(c, JobIdOf(name), true));
      if (row.job.state() == v1::QUEUED || row.job.state() == v1::RUNNING) {
        return absl::FailedPreconditionError(absl::StrCat(
            name, " is ", v1::JobState_Name(row.job.state()), "; cancel it before deleting it"));
      }
      // The tasks of a split job first, with it.
      for (const char* sql :
           {"DELETE FROM job_blobs WHERE job_id IN (SELECT id FROM jobs WHERE parent = $1)",
            "DELETE FROM jobs WHERE parent = $1", "DELETE FROM jobs WHERE id = $1",
            "DELETE FROM job_blobs WHERE job_id = $1"}) {
        SM_RETURN_IF_ERROR(c->Query(sql, {P(JobIdOf(name))}).status());
      }
      return absl::OkStatus();
    });
  }

  absl::StatusOr<int> RequeueExpired(int max_attempts, bool all, bool not_the_jobs_fault,
                                     std::vector<v1::Job>* ended) override {
    int n = 0;
    std::vector<v1::Job> gone;  // what the transaction ended (it may run more than once)
    SM_RETURN_IF_ERROR(pool_->Transaction([&](Conn& c) -> absl::Status {
      n = 0;
      gone.clear();
      // Rows another replica is requeueing are skipped, not waited for.
      SM_ASSIGN_OR_RETURN(
          PgResult q,
          all ? c->Query("SELECT id, job, cancel_requested FROM jobs WHERE state = $1 "
                         "FOR UPDATE SKIP LOCKED",
                         {P(int64_t{v1::RUNNING})})
              : c->Query(absl::StrCat("SELECT id, job, cancel_requested FROM jobs WHERE state = $1 "
                                      "AND lease_expires < ",
                                      kDbNowMs, " FOR UPDATE SKIP LOCKED"),
                         {P(int64_t{v1::RUNNING})}));
      for (int i = 0; i < q.rows(); ++i) {
        SM_ASSIGN_OR_RETURN(v1::Job job, ParseStoredJob(q.Bytes(i, 1)));
        ApplyLostWorker(&job, q.Text(i, 2) == "t", max_attempts, not_the_jobs_fault);
        SM_RETURN_IF_ERROR(SetState(c, q.Text(i, 0), job));
        if (job.state() != v1::QUEUED) gone.push_back(std::move(job));
        ++n;
      }
      return absl::OkStatus();
    }));
    if (ended != nullptr) std::move(gone.begin(), gone.end(), std::back_inserter(*ended));
    return n;
  }

  absl::StatusOr<std::optional<v1::Job>> FindCached(const std::string& key) override {
    SM_ASSIGN_OR_RETURN(Conn c, pool_->Get());
    SM_ASSIGN_OR_RETURN(PgResult q, c->Query("SELECT job FROM jobs WHERE cache_key = $1 AND "
                                             "state = $2 ORDER BY seq LIMIT 1",
                                             {P(key), P(int64_t{v1::SUCCEEDED})}));
    if (q.rows() == 0) return std::optional<v1::Job>();
    SM_ASSIGN_OR_RETURN(v1::Job j, ParseStoredJob(q.Bytes(0, 0)));
    return std::optional<v1::Job>(std::move(j));
  }

  absl::StatusOr<int64_t> CountInState(v1::JobState state) override {
    SM_ASSIGN_OR_RETURN(Conn c, pool_->Get());
    SM_ASSIGN_OR_RETURN(PgResult q,
                        c->Query("SELECT COUNT(*) FROM jobs WHERE state = $1 AND parent IS NULL",
                                 {P(int64_t{state})}));
    return q.Int(0, 0);
  }

  absl::StatusOr<int64_t> CountQueuedTasks() override {
    SM_ASSIGN_OR_RETURN(Conn c, pool_->Get());
    SM_ASSIGN_OR_RETURN(PgResult q,
                        c->Query("SELECT COUNT(*) FROM jobs WHERE state = $1 AND parent IS NOT NULL",
                                 {P(int64_t{v1::QUEUED})}));
    return q.Int(0, 0);
  }

  absl::Status AddUploadedBlob(const std::string& tenant, const std::string& hash) override {
    SM_ASSIGN_OR_RETURN(Conn c, pool_->Get());
    return c
        ->Query("INSERT INTO blob_owners (tenant, hash) VALUES ($1, $2) ON CONFLICT DO NOTHING",
                {P(tenant), P(hash)})
        .status();
  }

  absl::StatusOr<bool> OwnsBlob(const std::string& tenant, const std::string& hash) override {
    SM_ASSIGN_OR_RETURN(Conn c, pool_->Get());
    SM_ASSIGN_OR_RETURN(
        PgResult q, c->Query("SELECT 1 FROM blob_owners WHERE tenant = $1 AND hash = $2 "
                             "UNION ALL SELECT 1 FROM job_blobs b JOIN jobs j ON j.id = b.job_id "
                             "WHERE b.hash = $2 AND j.tenant = $1 LIMIT 1",
                             {P(tenant), P(hash)}));
    return q.rows() > 0;
  }

  absl::StatusOr<std::set<std::string>> ReferencedBlobs() override {
    SM_ASSIGN_OR_RETURN(Conn c, pool_->Get());
    SM_ASSIGN_OR_RETURN(PgResult q, c->Query("SELECT DISTINCT hash FROM job_blobs"));
    std::set<std::string> out;
    for (int i = 0; i < q.rows(); ++i) out.insert(q.Text(i, 0));
    return out;
  }

  absl::Status ForgetBlob(const std::string& hash) override {
    SM_ASSIGN_OR_RETURN(Conn c, pool_->Get());
    return c->Query("DELETE FROM blob_owners WHERE hash = $1", {P(hash)}).status();
  }

 private:
  struct Row {
    v1::Job job;
    std::string owner;
  };

  // Names a new job (NameNewJob) with the next number of the database's sequence (*seq).
  absl::StatusOr<std::string> NameNew(Conn& c, v1::Job* job, int64_t* seq) {
    SM_ASSIGN_OR_RETURN(PgResult q, c->Query("SELECT nextval('job_seq')"));
    *seq = q.Int(0, 0);
    std::lock_guard<std::mutex> lock(rng_mu_);
    return NameNewJob(job, *seq, rng_.Next());
  }

  static absl::Status NotRunningUnder(const std::string& name, const std::string& worker) {
    return absl::FailedPreconditionError(absl::StrCat(name, " is not running under ", worker));
  }

  // The row, locked for this transaction with `lock`.
  static absl::StatusOr<Row> RowOf(Conn& c, const std::string& id, bool lock) {
    SM_ASSIGN_OR_RETURN(PgResult q,
                        c->Query(lock ? "SELECT job, lease_owner FROM jobs WHERE id = $1 FOR UPDATE"
                                      : "SELECT job, lease_owner FROM jobs WHERE id = $1",
                                 {P(id)}));
    if (q.rows() == 0) return absl::NotFoundError(absl::StrCat("jobs/", id, " does not exist"));
    SM_ASSIGN_OR_RETURN(v1::Job j, ParseStoredJob(q.Bytes(0, 0)));
    return Row{std::move(j), q.null(0, 1) ? "" : q.Text(0, 1)};
  }

  absl::StatusOr<std::optional<v1::Job>> ByRequestId(const std::string& scoped) {
    SM_ASSIGN_OR_RETURN(Conn c, pool_->Get());
    SM_ASSIGN_OR_RETURN(PgResult q,
                        c->Query("SELECT job FROM jobs WHERE request_id = $1", {P(scoped)}));
    if (q.rows() == 0) return std::optional<v1::Job>();
    SM_ASSIGN_OR_RETURN(v1::Job j, ParseStoredJob(q.Bytes(0, 0)));
    return std::optional<v1::Job>(std::move(j));
  }

  static absl::Status SetState(Conn& c, const std::string& id, const v1::Job& job) {
    return c
        ->Query(
            "UPDATE jobs SET state = $1, lease_owner = NULL, lease_expires = NULL, job = $2 "
            "WHERE id = $3",
            {P(int64_t{job.state()}), J(job), P(id)})
        .status();
  }

  // The tasks of the merged job `id` drop their outputs (their input and plan are the job's).
  static absl::Status DropTaskOutputs(Conn& c, const std::string& id) {
    SM_ASSIGN_OR_RETURN(PgResult q,
                        c->Query("SELECT id, job FROM jobs WHERE parent = $1 FOR UPDATE", {P(id)}));
    for (int i = 0; i < q.rows(); ++i) {
      SM_ASSIGN_OR_RETURN(v1::Job task, ParseStoredJob(q.Bytes(i, 1)));
      ApplyMerged(&task);
      SM_RETURN_IF_ERROR(
          c->Query("UPDATE jobs SET job = $1 WHERE id = $2", {J(task), P(q.Text(i, 0))}).status());
    }
    return c
        ->Query("DELETE FROM job_blobs WHERE job_id IN (SELECT id FROM jobs WHERE parent = $1)",
                {P(id)})
        .status();
  }

  static absl::Status AddJobBlobs(Conn& c, const std::string& id, const v1::Job& job) {
    for (const std::string& hash : BlobsOf(job)) {
      SM_RETURN_IF_ERROR(c->Query("INSERT INTO job_blobs (job_id, hash) VALUES ($1, $2) "
                                  "ON CONFLICT DO NOTHING",
                                  {P(id), P(hash)})
                             .status());
    }
    return absl::OkStatus();
  }

  std::unique_ptr<PgPool> pool_;
  std::mutex rng_mu_;
  Rng rng_;
};

}  // namespace

absl::StatusOr<std::unique_ptr<JobStore>> OpenPostgresJobStore(const std::string& conninfo) {
  SM_ASSIGN_OR_RETURN(std::unique_ptr<PgPool> pool, PgPool::Open(conninfo, /*size=*/8));
  auto store = std::make_unique<PostgresJobStore>(std::move(pool));
  SM_RETURN_IF_ERROR(store->Init());
  return std::unique_ptr<JobStore>(std::move(store));
}

}  // namespace sheetmesh::server
