// The PostgreSQL test cluster (tools/pg_cluster.sh, started by ctest) for tests that use a
// real database: its connection string, and statements run outside any store (CREATE and
// DROP DATABASE).
#ifndef SHEETMESH_TESTS_TESTING_POSTGRES_CLUSTER_H_
#define SHEETMESH_TESTS_TESTING_POSTGRES_CLUSTER_H_

#include <libpq-fe.h>

#include <cstdlib>
#include <fstream>
#include <string>

namespace sheetmesh::testing {

// The cluster's connection string: $SHEETMESH_TEST_POSTGRES, or the file named by
// $SHEETMESH_TEST_POSTGRES_FILE; empty when neither is there (the test skips then).
inline std::string ClusterConninfo() {
  if (const char* c = std::getenv("SHEETMESH_TEST_POSTGRES"); c != nullptr && *c) return c;
  if (const char* f = std::getenv("SHEETMESH_TEST_POSTGRES_FILE"); f != nullptr && *f) {
    std::ifstream in(f);
    std::string line;
    if (std::getline(in, line)) return line;
  }
  return "";
}

inline constexpr char kNoClusterMessage[] =
    "no PostgreSQL test cluster (SHEETMESH_TEST_POSTGRES or SHEETMESH_TEST_POSTGRES_FILE; "
    "ctest starts one with tools/pg_cluster.sh where PostgreSQL is installed)";

// Runs one statement on its own connection; false with libpq's message in `error`.
inline bool Admin(const std::string& conninfo, const std::string& sql, std::string* error) {
  PGconn* c = PQconnectdb(conninfo.c_str());
  bool ok = PQstatus(c) == CONNECTION_OK;
  if (ok) {
    PGresult* r = PQexec(c, sql.c_str());
    ok = PQresultStatus(r) == PGRES_COMMAND_OK;
    PQclear(r);
  }
  if (!ok) *error = PQerrorMessage(c);
  PQfinish(c);
  return ok;
}

}  // namespace sheetmesh::testing

#endif  // SHEETMESH_TESTS_TESTING_POSTGRES_CLUSTER_H_
