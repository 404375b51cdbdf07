// The job events the servers of one PostgreSQL database share (postgres_events.h): two
// relays on a fresh database of the test cluster, each hooked to its own JobEvents as two
// servers' are; the cases that need the cluster skip with a message without it.
#include "server/postgres_events.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <libpq-fe.h>
#include <unistd.h>

#include <atomic>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "server/postgres_util.h"
#include "tests/testing/postgres_cluster.h"

namespace sheetmesh::server {
namespace {

using sheetmesh::testing::Admin;
using sheetmesh::testing::ClusterConninfo;
using ::testing::HasSubstr;

v1::JobProgress Stage(const std::string& name, int index) {
  v1::JobProgress p;
  p.set_stage(name);
  p.set_stage_index(index);
  p.set_fraction(0.25);
  p.set_message(absl::StrCat("brick ", index, " of 8"));
  return p;
}

TEST(PgEventRelayTest, AChangeIsOneNotifysPayloadAndBack) {
  for (JobEvent::Kind kind :
       {JobEvent::Kind::kChanged, JobEvent::Kind::kStage, JobEvent::Kind::kFinished}) {
    JobEvent e{kind, "jobs/0000000000000042", {}};
    if (kind == JobEvent::Kind::kStage) e.progress = Stage("surface", 7);
    const auto back = PgEventRelay::Decode(PgEventRelay::Encode("origin1", e));
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(back->first, "origin1");
    EXPECT_EQ(back->second.kind, kind);
    EXPECT_EQ(back->second.job, e.job);
    EXPECT_EQ(back->second.progress.SerializeAsString(), e.progress.SerializeAsString());
  }
  // A stage too long for NOTIFY is told as a change (its job holds the stage).
  JobEvent big{JobEvent::Kind::kStage, "jobs/1", Stage(std::string(9000, 'x'), 1)};
  const std::string payload = PgEventRelay::Encode("o", big);
  EXPECT_LT(payload.size(), 8000u);
  EXPECT_EQ(PgEventRelay::Decode(payload)->second.kind, JobEvent::Kind::kChanged);
  // What is not ours is passed by.
  for (const char* bad :
       {"", "o", "o\nc", "o\nq\njobs/1\n", "o\ns\njobs/1\n%%%", "\nc\njobs/1\n", "o\nc\n\n"}) {
    EXPECT_FALSE(PgEventRelay::Decode(bad).has_value()) << bad;
  }
}

// The relay's and the stores' connections: a default connect timeout unless given.
TEST(PgConnectTest, ADefaultConnectTimeoutUnlessTheConnectionStringGivesOne) {
  const auto timeout_of = [](const std::string& conninfo) {
    PGconn* c = PgConnect(conninfo);  // nothing listens on port 1: refused at once
    std::string value;
    PQconninfoOption* options = PQconninfo(c);
    for (PQconninfoOption* o = options; o != nullptr && o->keyword != nullptr; ++o) {
      if (std::string(o->keyword) == "connect_timeout" && o->val != nullptr) value = o->val;
    }
    PQconninfoFree(options);
    PQfinish(c);
    return value;
  };
  EXPECT_EQ(timeout_of("host=127.0.0.1 port=1 dbname=x"),
            std::to_string(kDefaultConnectTimeoutSeconds));
  EXPECT_EQ(timeout_of("host=127.0.0.1 port=1 dbname=x connect_timeout=3"), "3");
  EXPECT_EQ(timeout_of("postgresql://u@127.0.0.1:1/x"),
            std::to_string(kDefaultConnectTimeoutSeconds));
  EXPECT_EQ(timeout_of("postgresql://u@127.0.0.1:1/x?connect_timeout=7"), "7");
}

TEST(PgEventRelayTest, AnUnreachableDatabaseIsAClearError) {
  JobEvents events;
  auto relay = PgEventRelay::Start("host=127.0.0.1 port=1 connect_timeout=2", &events);
  ASSERT_FALSE(relay.ok());
  EXPECT_EQ(relay.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(relay.status().message(), HasSubstr("unreachable"));
}

class PgEventRelayClusterTest : public sheetmesh::testing::ClusterDatabaseTest {
 protected:
  PgEventRelayClusterTest() : ClusterDatabaseTest("events") {}
};

TEST_F(PgEventRelayClusterTest, WhatOneServerNotifiesTheOthersWatchersHearWithItsStages) {
  JobEvents a_events, b_events;
  auto a = PgEventRelay::Start(conninfo_, &a_events);
  auto b = PgEventRelay::Start(conninfo_, &b_events);
  ASSERT_TRUE(a.ok()) << a.status();
  ASSERT_TRUE(b.ok()) << b.status();
  const absl::Duration patience = absl::Seconds(20);  // not a timing: a change never told fails

  // A stage reported to server a reaches server b's watchers, with the stage.
  a_events.NotifyStage("jobs/x", Stage("bricks", 2));
  ASSERT_GT(b_events.Wait("jobs/x", 0, patience), 0u) << "b never heard";
  const auto stages = b_events.StagesSince("jobs/x", 0);
  ASSERT_EQ(stages.size(), 1u);
  EXPECT_EQ(stages[0].stage(), "bricks");
  EXPECT_EQ(stages[0].message(), "brick 2 of 8");

  // And back, a job's end; by then a's own stage has come back to a and was passed by.
  b_events.NotifyFinished("jobs/y");
  ASSERT_GT(a_events.Wait("jobs/y", 0, patience), 0u) << "a never heard";
  EXPECT_EQ(a_events.Version("jobs/x"), 1u) << "a applied its own change again";
  EXPECT_EQ(b_events.Version("jobs/y"), 1u) << "b applied its own change again";
  EXPECT_EQ((*a)->applied(), 1u);
  EXPECT_EQ((*b)->applied(), 1u);
  EXPECT_EQ((*a)->sent(), 1u);

  // Many changes of one job while it waits to be sent are told at least once, and the last
  // is heard.
  const uint64_t before = b_events.Version("jobs/z");
  for (int i = 0; i < 200; ++i) a_events.Notify("jobs/z");
  a_events.NotifyStage("jobs/z", Stage("merge", 3));
  for (absl::Time end = absl::Now() + patience; absl::Now() < end;) {
    if (!b_events.StagesSince("jobs/z", before).empty()) break;
    b_events.Wait("jobs/z", b_events.Version("jobs/z"), absl::Milliseconds(200));
  }
  ASSERT_EQ(b_events.StagesSince("jobs/z", before).size(), 1u);
  EXPECT_LE((*a)->sent(), 1u + 201u);

  // Unhooked, a relay sends nothing more.
  const uint64_t sent = (*a)->sent();
  a->reset();
  a_events.Notify("jobs/w");
  EXPECT_EQ(b_events.Wait("jobs/w", 0, absl::Milliseconds(500)), 0u);
  EXPECT_GE(sent, 2u);
}

}  // namespace
}  // namespace sheetmesh::server
