#include "server/sqlite_job_schema.h"

#include "common/status_macros.h"
#include "server/job_store_rows.h"
#include "server/sqlite_util.h"

namespace sheetmesh::server {
namespace {

// Whether table `jobs` has the column `name`.
absl::StatusOr<bool> HasColumn(sqlite3* db, const std::string& name) {
  Stmt q(db, "PRAGMA table_info(jobs)");
  SM_RETURN_IF_ERROR(q.ok());
  bool has = false;
  while (q.Step() == SQLITE_ROW) has |= q.Text(1) == name;
  return has;
}

// Stores written before tenants: the tenant column (their jobs are the default tenant's) and
// job_blobs filled from the jobs; before bricks: the column naming a brick task's job.
absl::Status Migrate(sqlite3* db) {
  SM_ASSIGN_OR_RETURN(const bool has_tenant, HasColumn(db, "tenant"));
  if (!has_tenant) {
    SM_RETURN_IF_ERROR(
        Exec(db, "ALTER TABLE jobs ADD COLUMN tenant TEXT NOT NULL DEFAULT 'default'"));
  }
  SM_RETURN_IF_ERROR(Exec(db, "CREATE INDEX IF NOT EXISTS jobs_tenant_seq ON jobs(tenant, seq)"));
  SM_ASSIGN_OR_RETURN(const bool has_parent, HasColumn(db, "parent"));
  if (!has_parent) SM_RETURN_IF_ERROR(Exec(db, "ALTER TABLE jobs ADD COLUMN parent TEXT"));
  SM_RETURN_IF_ERROR(Exec(db, "CREATE INDEX IF NOT EXISTS jobs_parent ON jobs(parent, state)"));
  bool has_job_blobs = false;
  {
    Stmt q(db, "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'job_blobs'");
    SM_RETURN_IF_ERROR(q.ok());
    has_job_blobs = q.Step() == SQLITE_ROW;
  }
  if (has_job_blobs) return absl::OkStatus();
  SM_RETURN_IF_ERROR(Exec(db, "BEGIN IMMEDIATE"));
  absl::Status st = [&]() -> absl::Status {
    SM_RETURN_IF_ERROR(Exec(db,
                            "CREATE TABLE job_blobs (job_id TEXT NOT NULL, hash TEXT NOT NULL,"
                            "  PRIMARY KEY (job_id, hash))"));
    SM_RETURN_IF_ERROR(Exec(db, "CREATE INDEX job_blobs_hash ON job_blobs(hash)"));
    Stmt q(db, "SELECT id, job FROM jobs");
    SM_RETURN_IF_ERROR(q.ok());
    while (q.Step() == SQLITE_ROW) {
      SM_ASSIGN_OR_RETURN(v1::Job j, ParseStoredJob(q.Blob(1)));
      SM_RETURN_IF_ERROR(AddSqliteJobBlobs(db, q.Text(0), j));
    }
    return absl::OkStatus();
  }();
  if (!st.ok()) {
    Exec(db, "ROLLBACK").IgnoreError();
    return st;
  }
  return Exec(db, "COMMIT");
}

}  // namespace

absl::Status InitSqliteJobSchema(sqlite3* db) {
  for (const char* sql : {
           "PRAGMA journal_mode=WAL",
           "PRAGMA synchronous=FULL",
           "PRAGMA busy_timeout=5000",
           "CREATE TABLE IF NOT EXISTS jobs ("
           "  id TEXT PRIMARY KEY, seq INTEGER NOT NULL, request_id TEXT UNIQUE NOT NULL,"
           "  state INTEGER NOT NULL, lease_owner TEXT, lease_expires INTEGER,"
           "  cancel_requested INTEGER NOT NULL DEFAULT 0, cache_key TEXT, job BLOB NOT NULL,"
           "  tenant TEXT NOT NULL DEFAULT 'default')",
           "CREATE INDEX IF NOT EXISTS jobs_state_seq ON jobs(state, seq)",
           "CREATE INDEX IF NOT EXISTS jobs_cache ON jobs(cache_key, state)",
           "CREATE TABLE IF NOT EXISTS blob_owners ("
           "  tenant TEXT NOT NULL, hash TEXT NOT NULL, PRIMARY KEY (tenant, hash))",
       }) {
    SM_RETURN_IF_ERROR(Exec(db, sql));
  }
  return Migrate(db);
}

absl::Status AddSqliteJobBlobs(sqlite3* db, const std::string& id, const v1::Job& job) {
  for (const std::string& hash : BlobsOf(job)) {
    Stmt q(db, "INSERT OR IGNORE INTO job_blobs (job_id, hash) VALUES (?, ?)");
    SM_RETURN_IF_ERROR(q.ok());
    q.Bind(1, id).Bind(2, hash);
    SM_RETURN_IF_ERROR(q.Run());
  }
  return absl::OkStatus();
}

}  // namespace sheetmesh::server
