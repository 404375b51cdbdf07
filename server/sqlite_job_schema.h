// The SQLite job store's tables: made when missing, and stores written by earlier versions
// brought up to date (the tenant column; the blobs each job names; the column naming a
// brick task's job).
#ifndef SHEETMESH_SERVER_SQLITE_JOB_SCHEMA_H_
#define SHEETMESH_SERVER_SQLITE_JOB_SCHEMA_H_

#include <sqlite3.h>

#include <string>

#include "absl/status/status.h"
#include "sheetmesh/v1/jobs.pb.h"

namespace sheetmesh::server {

// WAL journal, synchronous=FULL, the tables and their indexes, and the migrations.
absl::Status InitSqliteJobSchema(sqlite3* db);

// Records the blobs `job` names (its input and artifacts) as job `id`'s.
absl::Status AddSqliteJobBlobs(sqlite3* db, const std::string& id, const v1::Job& job);

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_SQLITE_JOB_SCHEMA_H_
