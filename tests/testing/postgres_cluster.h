// The PostgreSQL test cluster (tools/pg_cluster.sh, started by ctest) for tests that use a
// real database: its connection string, and statements run outside any store (CREATE and
// DROP DATABASE).
#ifndef SHEETMESH_TESTS_TESTING_POSTGRES_CLUSTER_H_
#define SHEETMESH_TESTS_TESTING_POSTGRES_CLUSTER_H_

#include <gtest/gtest.h>
#include <libpq-fe.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <string>
#include <utility>

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

// A fresh database of the cluster for each test, named from `prefix`, dropped after; the
// test skips without the cluster. conninfo_ reaches it.
class ClusterDatabaseTest : public ::testing::Test {
 protected:
  explicit ClusterDatabaseTest(std::string prefix) : prefix_(std::move(prefix)) {}
  void SetUp() override {
    cluster_ = ClusterConninfo();
    if (cluster_.empty()) GTEST_SKIP() << kNoClusterMessage;
    static std::atomic<int> n{0};
    db_ = prefix_ + "_" + std::to_string(getpid()) + "_" + std::to_string(n++);
    std::string error;
    ASSERT_TRUE(Admin(cluster_, "CREATE DATABASE " + db_, &error)) << error;
    conninfo_ = cluster_ + " dbname=" + db_;
  }
  void TearDown() override {
    if (db_.empty()) return;
    std::string error;
    EXPECT_TRUE(Admin(cluster_, "DROP DATABASE " + db_ + " WITH (FORCE)", &error)) << error;
  }
  std::string cluster_, db_, conninfo_;

 private:
  const std::string prefix_;
};

}  // namespace sheetmesh::testing

#endif  // SHEETMESH_TESTS_TESTING_POSTGRES_CLUSTER_H_
