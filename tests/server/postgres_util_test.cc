// PgPool's transactions against the test cluster: a transaction PostgreSQL rolls back as a
// deadlock's victim runs again, so both sides of a deadlock commit (two replicas finishing
// and requeueing the same jobs once lost a job's results to one). Skips without the cluster.
#include "server/postgres_util.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "tests/testing/postgres_cluster.h"

namespace sheetmesh::server {
namespace {

using ::testing::HasSubstr;

class PgPoolClusterTest : public sheetmesh::testing::ClusterDatabaseTest {
 protected:
  PgPoolClusterTest() : ClusterDatabaseTest("pool") {}
};

TEST_F(PgPoolClusterTest, ADeadlocksVictimRunsAgainAndBothTransactionsCommit) {
  auto pool = PgPool::Open(conninfo_, 4);
  ASSERT_TRUE(pool.ok()) << pool.status();
  ASSERT_TRUE((*pool)
                  ->Transaction([](PgPool::Lease& c) -> absl::Status {
                    if (absl::Status st = c->Exec("CREATE TABLE t (id INT PRIMARY KEY, v INT)");
                        !st.ok()) {
                      return st;
                    }
                    return c->Exec("INSERT INTO t VALUES (1, 0), (2, 0)");
                  })
                  .ok());
  // Each locks one row, waits until the other holds its row, then asks for the other's:
  // PostgreSQL finds the deadlock (after deadlock_timeout, a second) and rolls one back.
  std::atomic<int> runs{0}, holding{0};
  std::atomic<bool> aborted_seen{false};
  auto crossing = [&](int first, int second) {
    return (*pool)->Transaction([&, first, second](PgPool::Lease& c) -> absl::Status {
      const int run = ++runs;
      if (absl::Status st = c->Exec(absl::StrCat("UPDATE t SET v = v + 1 WHERE id = ", first));
          !st.ok()) {
        return st;
      }
      if (run <= 2) {  // the first two runs meet; a run again goes straight through
        ++holding;
        while (holding.load() < 2) absl::SleepFor(absl::Milliseconds(5));
      }
      absl::Status st = c->Exec(absl::StrCat("UPDATE t SET v = v + 1 WHERE id = ", second));
      if (absl::IsAborted(st)) {
        aborted_seen = true;
        EXPECT_THAT(st.message(), HasSubstr("deadlock"));
      }
      return st;
    });
  };
  absl::Status a, b;
  std::thread ta([&] { a = crossing(1, 2); });
  std::thread tb([&] { b = crossing(2, 1); });
  ta.join();
  tb.join();
  EXPECT_TRUE(a.ok()) << a;
  EXPECT_TRUE(b.ok()) << b;
  EXPECT_TRUE(aborted_seen.load()) << "PostgreSQL chose a victim";
  EXPECT_EQ(runs.load(), 3) << "the victim ran once more";
  // Each row was raised once by each transaction that committed, and the victim's first
  // run left nothing.
  auto c = (*pool)->Get();
  ASSERT_TRUE(c.ok()) << c.status();
  auto q = (*c)->Query("SELECT v FROM t ORDER BY id");
  ASSERT_TRUE(q.ok()) << q.status();
  ASSERT_EQ(q->rows(), 2);
  EXPECT_EQ(q->Text(0, 0), "2");
  EXPECT_EQ(q->Text(1, 0), "2");
}

}  // namespace
}  // namespace sheetmesh::server
