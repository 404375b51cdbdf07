// One conformance suite for every JobStore: SQLite in a temporary folder, PostgreSQL in a
// fresh database of the test cluster (tools/pg_cluster.sh, started by ctest; the
// PostgreSQL cases skip with a message where no cluster is given), and the in-memory store
// on a manual clock (leases end when the test moves the clock, not when time passes).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <libpq-fe.h>

#include <atomic>
#include <fstream>
#include <set>
#include <thread>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "server/job_store.h"
#include "server/job_store_rows.h"
#include "server/memory_job_store.h"
#include "tests/testing/postgres_cluster.h"
#include "tests/testing/temp_dir.h"

namespace sheetmesh::server {
namespace {

using sheetmesh::testing::Admin;
using sheetmesh::testing::ClusterConninfo;
using sheetmesh::testing::TempDir;
using ::testing::HasSubstr;

class JobStoreConformanceTest : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    if (GetParam() == "postgres") {
      cluster_ = ClusterConninfo();
      if (cluster_.empty()) {
        GTEST_SKIP() << sheetmesh::testing::kNoClusterMessage;
      }
      static std::atomic<int> n{0};
      db_ = absl::StrCat("conformance_", getpid(), "_", n++);
      std::string error;
      ASSERT_TRUE(Admin(cluster_, "CREATE DATABASE " + db_, &error)) << error;
    }
    Open();
  }
  void TearDown() override {
    store_.reset();
    if (!db_.empty()) {
      std::string error;
      EXPECT_TRUE(Admin(cluster_, "DROP DATABASE " + db_ + " WITH (FORCE)", &error)) << error;
    }
  }

  // (Re)opens the store on the same data: a restart.
  void Open() {
    store_.reset();
    store_ = Another();
    ASSERT_NE(store_, nullptr);
  }
  // Another store on the same data, as another replica (or another thread's) sees it.
  std::unique_ptr<JobStore> Another() {
    if (GetParam() == "memory") return OpenMemoryJobStore(tables_, clock_.AsStoreClock());
    auto s = GetParam() == "postgres" ? OpenPostgresJobStore(Conninfo())
                                      : OpenSqliteJobStore(dir_.File("jobs.db"));
    EXPECT_TRUE(s.ok()) << s.status();
    return s.ok() ? std::move(*s) : nullptr;
  }
  // Lets `d` pass for the leases: the manual clock moves; the databases' clock is the
  // system's, so the test waits.
  void PassTime(absl::Duration d) {
    if (GetParam() == "memory") {
      clock_.Advance(d);
    } else {
      absl::SleepFor(d);
    }
  }
  std::string Conninfo() const { return absl::StrCat(cluster_, " dbname=", db_); }

  static v1::Job NewJob(const std::string& request_id) {
    v1::Job j;
    j.set_request_id(request_id);
    j.mutable_input()->set_volume_path("/data/" + request_id);
    j.set_pipeline_version("test");
    return j;
  }
  std::string Add(const std::string& request_id, const std::string& key = "") {
    bool created = false;
    auto j = store_->Create(NewJob(request_id), key, &created);
    EXPECT_TRUE(j.ok() && created) << j.status();
    return j.ok() ? j->name() : "";
  }

  TempDir dir_;
  std::string cluster_, db_;
  std::shared_ptr<MemoryJobTables> tables_ = NewMemoryJobTables();
  ManualClock clock_;
  std::unique_ptr<JobStore> store_;
};

TEST_P(JobStoreConformanceTest, CreateIsIdempotentByRequestIdWithinATenant) {
  bool created = false;
  auto a = store_->Create(NewJob("r1"), "k1", &created);
  ASSERT_TRUE(a.ok()) << a.status();
  EXPECT_TRUE(created);
  EXPECT_EQ(a->state(), v1::QUEUED);
  EXPECT_THAT(a->name(), ::testing::StartsWith("jobs/"));
  auto b = store_->Create(NewJob("r1"), "k1", &created);
  ASSERT_TRUE(b.ok());
  EXPECT_FALSE(created);
  EXPECT_EQ(a->name(), b->name());
  v1::Job other = NewJob("r1");
  other.set_tenant("alice");
  auto c = store_->Create(other, "k1", &created);
  ASSERT_TRUE(c.ok() && created) << "the same request id in another tenant is another job";
  EXPECT_NE(c->name(), a->name());
  auto found = store_->FindByRequestId("default", "r1");
  ASSERT_TRUE(found.ok() && found->has_value());
  EXPECT_EQ((*found)->name(), a->name());
  EXPECT_EQ(store_->Get("jobs/none").status().code(), absl::StatusCode::kNotFound);
}

TEST_P(JobStoreConformanceTest, ConcurrentCreatesOfOneRequestMakeOneJob) {
  std::vector<std::unique_ptr<JobStore>> replicas;
  for (int i = 0; i < 4; ++i) replicas.push_back(Another());
  std::vector<std::string> names(8);
  std::atomic<int> made{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&, t] {
      bool created = false;
      auto j = replicas[t % 4]->Create(NewJob("same"), "", &created);
      if (j.ok()) names[t] = j->name();
      made += created;
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(made.load(), 1);
  EXPECT_THAT(names, ::testing::Each(names[0]));
}

TEST_P(JobStoreConformanceTest, LeasingIsExclusiveUnderEightLeasers) {
  constexpr int kJobs = 60;
  for (int i = 0; i < kJobs; ++i) Add(absl::StrCat("r", i));
  std::vector<std::unique_ptr<JobStore>> replicas;
  for (int i = 0; i < 4; ++i) replicas.push_back(Another());
  std::mutex mu;
  std::vector<std::string> leased;
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&, t] {
      JobStore& s = *replicas[t % 4];
      for (;;) {
        auto l = s.LeaseNext(absl::StrCat("w", t), absl::Seconds(60));
        ASSERT_TRUE(l.ok()) << l.status();
        if (!l->has_value()) return;
        ASSERT_TRUE(s.Finish((*l)->name(), absl::StrCat("w", t), v1::SUCCEEDED, {}, {}).ok());
        std::lock_guard<std::mutex> lock(mu);
        leased.push_back((*l)->name());
      }
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(leased.size(), static_cast<size_t>(kJobs));
  EXPECT_EQ(std::set<std::string>(leased.begin(), leased.end()).size(), leased.size())
      << "a job was leased twice";
  EXPECT_EQ(*store_->CountInState(v1::SUCCEEDED), kJobs);
}

TEST_P(JobStoreConformanceTest, LeaseRenewProgressFinishAndTheCache) {
  const std::string first = Add("r1", "k1"), second = Add("r2", "k2");
  auto l1 = store_->LeaseNext("w1", absl::Seconds(30));
  ASSERT_TRUE(l1.ok() && l1->has_value());
  EXPECT_EQ((*l1)->name(), first);  // oldest first
  EXPECT_EQ((*l1)->state(), v1::RUNNING);
  EXPECT_EQ((*l1)->attempts(), 1);
  EXPECT_TRUE(store_->Renew(first, "w1", absl::Seconds(30)).ok());
  EXPECT_EQ(store_->Renew(first, "w2", absl::Seconds(30)).code(),
            absl::StatusCode::kFailedPrecondition);
  v1::JobProgress p;
  p.set_stage("surface");
  p.set_stage_index(3);
  ASSERT_TRUE(store_->SetProgress(first, "w1", p).ok());
  EXPECT_EQ(store_->SetProgress(first, "w2", p).code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(store_->Get(first)->progress().stage(), "surface");
  v1::Artifact art;
  art.set_name("report.json");
  art.mutable_digest()->set_hash(std::string(64, 'b'));
  // A worker that no longer holds the job cannot finish it; the job is unchanged.
  EXPECT_EQ(store_->Finish(first, "w2", v1::SUCCEEDED, {}, {art}).status().code(),
            absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(store_->Get(first)->state(), v1::RUNNING);
  auto done = store_->Finish(first, "w1", v1::SUCCEEDED, {}, {art});
  ASSERT_TRUE(done.ok()) << done.status();
  EXPECT_EQ(done->artifacts_size(), 1);
  auto cached = store_->FindCached("k1");
  ASSERT_TRUE(cached.ok() && cached->has_value());
  EXPECT_EQ((*cached)->name(), first);
  EXPECT_FALSE(store_->FindCached("k2")->has_value());
  EXPECT_EQ(*store_->CountInState(v1::QUEUED), 1);
  EXPECT_TRUE(*store_->OwnsBlob("default", std::string(64, 'b'))) << "its artifact";
  EXPECT_EQ(*store_->ReferencedBlobs(), std::set<std::string>{std::string(64, 'b')});
  // Release puts a job back without counting the attempt.
  auto l2 = store_->LeaseNext("w1", absl::Seconds(30));
  ASSERT_TRUE(l2.ok() && l2->has_value());
  ASSERT_TRUE(store_->Release(second, "w1").ok());
  EXPECT_EQ(store_->Get(second)->state(), v1::QUEUED);
  EXPECT_EQ(store_->Get(second)->attempts(), 0);
}

TEST_P(JobStoreConformanceTest, ExpiredLeasesRequeueThenFailAfterMaxAttemptsWithTheReason) {
  const std::string job = Add("r1");
  for (int attempt = 1; attempt <= 2; ++attempt) {
    auto l = store_->LeaseNext("w", absl::Milliseconds(1));
    ASSERT_TRUE(l.ok() && l->has_value());
    EXPECT_EQ((*l)->attempts(), attempt);
    PassTime(absl::Milliseconds(30));
    std::vector<v1::Job> ended;
    EXPECT_EQ(*store_->RequeueExpired(2, false, false, &ended), 1);
    // Only the end is told: the first loss requeued it.
    ASSERT_EQ(ended.size(), attempt == 2 ? 1u : 0u);
    if (attempt == 2) {
      EXPECT_EQ(ended[0].name(), job);
      EXPECT_EQ(ended[0].state(), v1::FAILED);
    }
  }
  auto end = store_->Get(job);
  ASSERT_TRUE(end.ok());
  EXPECT_EQ(end->state(), v1::FAILED);
  EXPECT_THAT(end->error().message(), HasSubstr("max_attempts = 2"));
  // A live lease is not requeued.
  const std::string live = Add("r2");
  ASSERT_TRUE(store_->LeaseNext("w", absl::Hours(1))->has_value());
  EXPECT_EQ(*store_->RequeueExpired(2, false), 0);
  EXPECT_EQ(store_->Get(live)->state(), v1::RUNNING);
}

TEST_P(JobStoreConformanceTest, ARestartKeepsEverythingAndRequeuesRunningJobs) {
  const std::string name = Add("r1");
  ASSERT_TRUE(store_->LeaseNext("w", absl::Hours(1))->has_value());
  Open();
  EXPECT_EQ(*store_->RequeueExpired(3, /*all=*/true), 1);
  auto job = store_->Get(name);
  ASSERT_TRUE(job.ok());
  EXPECT_EQ(job->state(), v1::QUEUED);
  EXPECT_EQ(job->attempts(), 1);
  auto again = store_->LeaseNext("w2", absl::Seconds(30));
  ASSERT_TRUE(again.ok() && again->has_value());
  EXPECT_EQ((*again)->attempts(), 2);
}

TEST_P(JobStoreConformanceTest, CancelQueuedAtOnceRunningByRequestAndDeleteOnlyFinished) {
  const std::string first = Add("q"), second = Add("r");
  ASSERT_TRUE(store_->LeaseNext("w", absl::Seconds(30))->has_value());  // the first runs
  auto c1 = store_->RequestCancel(second);
  ASSERT_TRUE(c1.ok());
  EXPECT_EQ(c1->state(), v1::CANCELLED);
  auto c2 = store_->RequestCancel(first);
  ASSERT_TRUE(c2.ok());
  EXPECT_EQ(c2->state(), v1::RUNNING);
  EXPECT_TRUE(*store_->CancelRequested(first));
  EXPECT_EQ(store_->Delete(first).code(), absl::StatusCode::kFailedPrecondition);
  v1::JobError e;
  e.set_code(1);
  ASSERT_TRUE(store_->Finish(first, "w", v1::CANCELLED, e, {}).ok());
  EXPECT_TRUE(store_->Delete(first).ok());
  EXPECT_EQ(store_->Get(first).status().code(), absl::StatusCode::kNotFound);
  // A cancel asked of a job whose worker is then lost ends it CANCELLED, not QUEUED.
  const std::string third = Add("t");
  ASSERT_TRUE(store_->LeaseNext("w", absl::Milliseconds(1))->has_value());
  ASSERT_TRUE(store_->RequestCancel(third).ok());
  PassTime(absl::Milliseconds(30));
  EXPECT_EQ(*store_->RequeueExpired(3, false), 1);
  EXPECT_EQ(store_->Get(third)->state(), v1::CANCELLED);
}

TEST_P(JobStoreConformanceTest, ListPagesNewestFirstByStateAndTenant) {
  std::vector<std::string> names;
  for (int i = 0; i < 7; ++i) names.push_back(Add(absl::StrCat("r", i)));
  std::vector<std::string> seen;
  std::string token, next;
  do {
    auto page = store_->List("default", v1::JOB_STATE_UNSPECIFIED, 3, token, &next);
    ASSERT_TRUE(page.ok()) << page.status();
    for (const auto& j : *page) seen.push_back(j.name());
    token = next;
  } while (!token.empty());
  EXPECT_EQ(seen, std::vector<std::string>(names.rbegin(), names.rend()));
  EXPECT_TRUE(store_->List("default", v1::RUNNING, 10, "", &next)->empty());
  EXPECT_TRUE(store_->List("alice", v1::JOB_STATE_UNSPECIFIED, 10, "", &next)->empty());
  EXPECT_EQ(store_->List("default", v1::QUEUED, 10, "garbage", &next).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST_P(JobStoreConformanceTest, BlobOwnersByUploadAndByJob) {
  bool created = false;
  v1::Job a = NewJob("same");
  a.set_tenant("alice");
  a.mutable_input()->mutable_volume_digest()->set_hash(std::string(64, 'a'));
  ASSERT_TRUE(store_->Create(a, "", &created).ok());
  EXPECT_TRUE(*store_->OwnsBlob("alice", std::string(64, 'a'))) << "her job's input";
  EXPECT_FALSE(*store_->OwnsBlob("bob", std::string(64, 'a')));
  ASSERT_TRUE(store_->AddUploadedBlob("bob", std::string(64, 'b')).ok());
  ASSERT_TRUE(store_->AddUploadedBlob("bob", std::string(64, 'b')).ok());  // again: no error
  EXPECT_TRUE(*store_->OwnsBlob("bob", std::string(64, 'b')));
  EXPECT_FALSE(*store_->OwnsBlob("alice", std::string(64, 'b')));
  EXPECT_EQ(*store_->ReferencedBlobs(), std::set<std::string>{std::string(64, 'a')});
  ASSERT_TRUE(store_->ForgetBlob(std::string(64, 'b')).ok());
  EXPECT_FALSE(*store_->OwnsBlob("bob", std::string(64, 'b')));
}

// Hardening, third round: a job of 21,504 bricks took 54 s to cancel, one transaction per
// task, and its tasks did not count in the queue. CancelTasks is one call (its time is in
// bench/hardening3_bench.py), and queued tasks are counted apart.
TEST_P(JobStoreConformanceTest, TheTasksOfASplitJobAreCountedAndCancelledAtOnce) {
  bool created = false;
  v1::Job bricked = NewJob("big");
  bricked.mutable_bricks()->set_size("auto");
  auto made = store_->Create(bricked, "k", &created);
  ASSERT_TRUE(made.ok()) << made.status();
  const std::string job = made->name();
  ASSERT_TRUE(store_->LeaseNext("w1", absl::Seconds(30))->has_value());
  v1::Artifact plan;
  plan.set_name("plan.json");
  plan.mutable_digest()->set_hash(std::string(64, 'p'));
  constexpr int kTasks = 1000;
  auto split = store_->Split(job, "w1", plan, kTasks);
  ASSERT_TRUE(split.ok()) << split.status();
  EXPECT_EQ(*store_->CountQueuedTasks(), kTasks);
  EXPECT_EQ(*store_->CountInState(v1::QUEUED), 1);
  auto running = store_->LeaseNext("w2", absl::Seconds(30));  // the first brick runs
  ASSERT_TRUE(running.ok() && running->has_value());
  ASSERT_EQ((*running)->bricks().parent(), job);
  EXPECT_EQ(*store_->CountQueuedTasks(), kTasks - 1);
  EXPECT_EQ(*store_->CancelTasks(job), kTasks);
  EXPECT_EQ(*store_->CountQueuedTasks(), 0);
  auto tasks = store_->Tasks(job);
  ASSERT_TRUE(tasks.ok()) << tasks.status();
  int cancelled = 0;
  for (const v1::Job& t : *tasks) {
    if (t.name() == (*running)->name()) {
      EXPECT_EQ(t.state(), v1::RUNNING);
      EXPECT_TRUE(*store_->CancelRequested(t.name())) << "its worker is told to stop";
      continue;
    }
    EXPECT_EQ(t.state(), v1::CANCELLED);
    EXPECT_EQ(t.error().code(), static_cast<int>(absl::StatusCode::kCancelled));
    EXPECT_TRUE(t.has_end_time());
    cancelled += t.state() == v1::CANCELLED;
  }
  EXPECT_EQ(cancelled, kTasks - 1);
  EXPECT_EQ(*store_->CancelTasks(job), 1) << "again: only the running one is touched";
  EXPECT_EQ(*store_->CancelTasks(Add("plain")), 0) << "a job that is not split";
}

TEST_P(JobStoreConformanceTest, ASplitJobWaitsForItsBricksThenComesBackToBeMerged) {
  bool created = false;
  v1::Job bricked = NewJob("big");
  bricked.mutable_bricks()->set_size("auto");
  auto made = store_->Create(bricked, "k", &created);
  ASSERT_TRUE(made.ok()) << made.status();
  const std::string job = made->name(), other = Add("small");
  auto l = store_->LeaseNext("w1", absl::Seconds(30));
  ASSERT_TRUE(l.ok() && l->has_value());
  ASSERT_EQ((*l)->name(), job);
  v1::Artifact plan;
  plan.set_name("plan.json");
  plan.mutable_digest()->set_hash(std::string(64, 'p'));
  EXPECT_EQ(store_->Split(job, "w2", plan, 3).status().code(),
            absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(store_->Split(job, "w1", plan, 0).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(store_->Split(job, "w1", plan, kMaxBricks + 1).status().code(),
            absl::StatusCode::kInvalidArgument);
  auto split = store_->Split(job, "w1", plan, 3);
  ASSERT_TRUE(split.ok()) << split.status();
  EXPECT_EQ(split->state(), v1::QUEUED);
  EXPECT_EQ(split->attempts(), 0) << "planning is not an attempt";
  EXPECT_EQ(split->bricks().count(), 3);
  ASSERT_EQ(split->bricks().tasks_size(), 3);
  EXPECT_EQ(store_->Split(job, "w1", plan, 3).status().code(),
            absl::StatusCode::kFailedPrecondition)
      << "split once";
  Open();  // the split survives a restart
  auto tasks = store_->Tasks(job);
  ASSERT_TRUE(tasks.ok()) << tasks.status();
  ASSERT_EQ(tasks->size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const v1::Job& t = (*tasks)[i];
    EXPECT_EQ(t.name(), split->bricks().tasks(i));
    EXPECT_EQ(t.bricks().parent(), job);
    EXPECT_EQ(t.bricks().index(), i);
    EXPECT_EQ(t.bricks().plan().digest().hash(), plan.digest().hash());
    EXPECT_EQ(t.input().volume_path(), "/data/big");
    EXPECT_EQ(t.state(), v1::QUEUED);
  }
  EXPECT_TRUE(store_->Tasks(other)->empty());
  EXPECT_EQ(*store_->CountInState(v1::QUEUED), 2) << "the job and the other; not its bricks";
  EXPECT_TRUE(store_->ReferencedBlobs()->count(std::string(64, 'p'))) << "the plan is kept";
  std::string next;
  EXPECT_EQ(store_->List("default", v1::JOB_STATE_UNSPECIFIED, 10, "", &next)->size(), 2u)
      << "bricks are not listed";
  // The older job first, then the bricks in order; the split job waits for them.
  std::vector<std::string> leased;
  for (int i = 0; i < 4; ++i) {
    auto n =
        store_->LeaseNext(absl::StrCat("w", i), i == 3 ? absl::Milliseconds(1) : absl::Seconds(30));
    ASSERT_TRUE(n.ok() && n->has_value());
    leased.push_back((*n)->name());
  }
  EXPECT_EQ(leased, (std::vector<std::string>{other, split->bricks().tasks(0),
                                              split->bricks().tasks(1), split->bricks().tasks(2)}));
  EXPECT_FALSE(store_->LeaseNext("w", absl::Seconds(30))->has_value());
  v1::Artifact out;
  out.set_name("brick_0.bin");
  out.mutable_digest()->set_hash(std::string(64, 'c'));
  ASSERT_TRUE(store_->Finish(leased[1], "w1", v1::SUCCEEDED, {}, {out}).ok());
  ASSERT_TRUE(store_->Finish(leased[2], "w2", v1::SUCCEEDED, {}, {out}).ok());
  EXPECT_FALSE(store_->LeaseNext("w", absl::Seconds(30))->has_value()) << "a brick still runs";
  // The last brick's worker is lost: the brick runs again, and only then the merge.
  PassTime(absl::Milliseconds(30));
  EXPECT_EQ(*store_->RequeueExpired(3, false), 1);
  auto again = store_->LeaseNext("w9", absl::Seconds(30));
  ASSERT_TRUE(again.ok() && again->has_value());
  EXPECT_EQ((*again)->name(), leased[3]);
  EXPECT_EQ((*again)->attempts(), 2);
  ASSERT_TRUE(store_->Finish(leased[3], "w9", v1::SUCCEEDED, {}, {out}).ok());
  auto merge = store_->LeaseNext("w5", absl::Seconds(30));
  ASSERT_TRUE(merge.ok() && merge->has_value());
  EXPECT_EQ((*merge)->name(), job);
  EXPECT_EQ((*merge)->attempts(), 1);
  EXPECT_EQ((*merge)->bricks().count(), 3);
  EXPECT_TRUE(store_->ReferencedBlobs()->count(std::string(64, 'c'))) << "to be merged";
  ASSERT_TRUE(store_->Finish(job, "w5", v1::SUCCEEDED, {}, {}).ok());
  // Merged: the bricks' outputs are let go (the tasks stay, without them).
  EXPECT_FALSE(store_->ReferencedBlobs()->count(std::string(64, 'c')));
  EXPECT_EQ(store_->Get(leased[1])->artifacts_size(), 0);
  EXPECT_EQ(store_->Get(leased[1])->state(), v1::SUCCEEDED);
  EXPECT_TRUE(store_->ReferencedBlobs()->count(std::string(64, 'p'))) << "the job's plan stays";
  // Deleting the job deletes its bricks; a brick alone is not deleted by the store's caller
  // (the service refuses it), but the store takes them with their job.
  ASSERT_TRUE(store_->Delete(job).ok());
  for (const std::string& t : split->bricks().tasks()) {
    EXPECT_EQ(store_->Get(t).status().code(), absl::StatusCode::kNotFound) << t;
  }
  EXPECT_FALSE(store_->ReferencedBlobs()->count(std::string(64, 'c')));
}

INSTANTIATE_TEST_SUITE_P(Stores, JobStoreConformanceTest,
                         ::testing::Values("sqlite", "postgres", "memory"),
                         [](const auto& info) { return info.param; });

TEST(PostgresJobStoreTest, AnUnreachableServerIsUnavailableNamingTheAddress) {
  auto s = OpenPostgresJobStore("host=127.0.0.1 port=1 dbname=nothing connect_timeout=2");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(s.status().message(), HasSubstr("PostgreSQL at 127.0.0.1:1 (database nothing)"));
  auto bad = OpenPostgresJobStore("host=127.0.0.1 port= = =");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace sheetmesh::server

namespace sheetmesh::server {
namespace {

// The manual clock decides: a lease of 30 s holds at 29 s and ends after 30 s, and the
// job's times are the clock's.
TEST(MemoryJobStoreTest, LeasesEndAndTimesAreStampedByTheGivenClock) {
  ManualClock clock;
  std::unique_ptr<JobStore> store = OpenMemoryJobStore(NewMemoryJobTables(), clock.AsStoreClock());
  v1::Job j;
  j.set_request_id("r");
  bool created = false;
  ASSERT_TRUE(store->Create(j, "", &created).ok());
  auto leased = store->LeaseNext("w", absl::Seconds(30));
  ASSERT_TRUE(leased.ok() && leased->has_value());
  EXPECT_EQ((*leased)->start_time().seconds(), absl::ToUnixSeconds(clock.Now()));
  clock.Advance(absl::Seconds(29));
  EXPECT_EQ(*store->RequeueExpired(3, false), 0);
  ASSERT_TRUE(store->Renew((*leased)->name(), "w", absl::Seconds(30)).ok());
  clock.Advance(absl::Seconds(29));
  EXPECT_EQ(*store->RequeueExpired(3, false), 0) << "renewed at 29 s, so until 59 s";
  clock.Advance(absl::Seconds(2));
  EXPECT_EQ(*store->RequeueExpired(3, false), 1);
  EXPECT_EQ(store->Get((*leased)->name())->state(), v1::QUEUED);
}

}  // namespace
}  // namespace sheetmesh::server
