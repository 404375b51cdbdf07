// Jobs run as bricks on the service's queue, over real gRPC on loopback: a job planned by a
// worker, split into brick tasks that any worker leases, merged once they have all ended —
// the same surface as one process; a failed brick fails the job naming it; a cancel reaches
// every brick; bad brick sizes are refused naming the field.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "grpcpp/create_channel.h"
#include "grpcpp/security/credentials.h"
#include "sheetmesh/v1/workers.grpc.pb.h"
#include "server/bricked_jobs.h"
#include "server/memory_job_store.h"
#include "tests/server/service_fixture.h"

namespace sheetmesh::testing {
namespace {

using ::testing::HasSubstr;

std::map<std::string, std::string> ArtifactHashes(const v1::Job& job) {
  std::map<std::string, std::string> out;
  for (const v1::Artifact& a : job.artifacts()) out[a.name()] = a.digest().hash();
  return out;
}

TEST_F(ServiceTest, ABrickedJobRunsAsBrickTasksAndGivesTheOneProcessSurface) {
  StartServer();
  const std::string vol = WritePhantom(options_.allowed_roots[0], "rock", 48, 21);
  v1::CreateJobRequest whole;
  whole.set_request_id("whole");
  whole.mutable_input()->set_volume_path(vol);
  whole.mutable_parameters()->set_extract(false);
  whole.set_no_cache(true);
  // The bricked job reads an upload: each brick task resolves its input on its own.
  auto digest = client_->Upload(vol);
  ASSERT_TRUE(digest.ok()) << digest.status();
  v1::CreateJobRequest bricked = UploadRequest(*digest, "rock_48x48x48_u8.raw", "bricked");
  bricked.mutable_parameters()->set_extract(false);
  bricked.set_no_cache(true);
  bricked.set_bricks("16x16x24");  // 3 x 3 x 2 bricks, cutting through the sheets
  auto a = client_->CreateJob(whole);
  ASSERT_TRUE(a.ok()) << a.status();
  auto b = client_->CreateJob(bricked);
  ASSERT_TRUE(b.ok()) << b.status();
  EXPECT_EQ(b->bricks().size(), "16x16x24");
  std::set<std::string> brick_messages;
  std::vector<v1::JobState> states;
  auto done = client_->Watch(b->name(), [&](const v1::WatchJobResponse& r) {
    if (states.empty() || states.back() != r.job().state()) states.push_back(r.job().state());
    if (r.job().progress().stage() == "bricks") brick_messages.insert(r.job().progress().message());
  });
  ASSERT_TRUE(done.ok()) << done.status();
  ASSERT_EQ(done->state(), v1::SUCCEEDED) << done->error().message();
  const v1::Job one = WaitFinished(a->name());
  ASSERT_EQ(one.state(), v1::SUCCEEDED) << one.error().message();
  // A watcher sees the job run from start to end, never queued again in between.
  EXPECT_EQ(states.back(), v1::SUCCEEDED);
  for (size_t i = 1; i < states.size(); ++i) EXPECT_NE(states[i], v1::QUEUED);
  EXPECT_FALSE(brick_messages.empty()) << "no progress of the bricks was streamed";
  for (const std::string& m : brick_messages) EXPECT_THAT(m, HasSubstr("18 bricks done")) << m;
  // The same surface, byte for byte, and the merge's account of the bricks.
  const auto mine = ArtifactHashes(*done), theirs = ArtifactHashes(one);
  ASSERT_TRUE(mine.count("surface.ply") && theirs.count("surface.ply"));
  EXPECT_EQ(mine.at("surface.ply"), theirs.at("surface.ply"));
  EXPECT_TRUE(mine.count("bricks.json"));
  for (const auto& [name, hash] : theirs) EXPECT_TRUE(mine.count(name)) << name;
  // The brick tasks: each ran once; their files were let go once merged; not listed with
  // the jobs.
  ASSERT_EQ(done->bricks().count(), 18);
  ASSERT_EQ(done->bricks().tasks_size(), 18);
  EXPECT_EQ(client_->GetJob(done->name())->bricks().succeeded(), 18);
  for (int i = 0; i < 18; ++i) {
    auto t = client_->GetJob(done->bricks().tasks(i));
    ASSERT_TRUE(t.ok()) << t.status();
    EXPECT_EQ(t->state(), v1::SUCCEEDED);
    EXPECT_EQ(t->bricks().parent(), done->name());
    EXPECT_EQ(t->bricks().index(), i);
    EXPECT_EQ(t->artifacts_size(), 0);
    EXPECT_EQ(t->attempts(), 1);
  }
  v1::ListJobsRequest lr;
  v1::ListJobsResponse listed;
  ASSERT_TRUE(client_->jobs()->ListJobs(client_->Context().get(), lr, &listed).ok());
  EXPECT_EQ(listed.jobs_size(), 2);
  // A brick goes with its job, not alone.
  v1::DeleteJobRequest del;
  v1::DeleteJobResponse deleted;
  del.set_name(done->bricks().tasks(0));
  const grpc::Status alone = client_->jobs()->DeleteJob(client_->Context().get(), del, &deleted);
  EXPECT_EQ(alone.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(alone.error_message(), HasSubstr("brick 0 of " + done->name()));
  del.set_name(done->name());
  ASSERT_TRUE(client_->jobs()->DeleteJob(client_->Context().get(), del, &deleted).ok());
  EXPECT_EQ(client_->GetJob(done->bricks().tasks(0)).status().code(), absl::StatusCode::kNotFound);
}

TEST_F(ServiceTest, BadBrickSizesAreRefusedNamingTheFieldAndWhatBricksCannotRunFailsTheJob) {
  StartServer();
  const std::string vol = WritePhantom(options_.allowed_roots[0], "rock", 24, 22);
  int i = 0;
  for (const std::string bad : {"abc", "-4", "8x8", "8x-1x8", "1e3"}) {
    v1::CreateJobRequest r;
    r.set_request_id(absl::StrCat("bad-", i++));
    r.mutable_input()->set_volume_path(vol);
    r.set_bricks(bad);
    auto job = client_->CreateJob(r);
    EXPECT_EQ(job.status().code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_THAT(job.status().message(), HasSubstr("bricks '" + bad + "'"));
  }
  // The grey levels' sheet detection looks around each voxel: the plan refuses it, and the
  // job fails saying so.
  v1::CreateJobRequest r;
  r.set_request_id("grey");
  r.mutable_input()->set_volume_path(vol);
  r.mutable_parameters()->set_config_json(R"({"input": {"grey": true}})");
  r.set_bricks("auto");
  auto job = client_->CreateJob(r);
  ASSERT_TRUE(job.ok()) << job.status();
  const v1::Job end = WaitFinished(job->name());
  EXPECT_EQ(end.state(), v1::FAILED);
  EXPECT_THAT(end.error().message(), HasSubstr("input.grey"));
  EXPECT_EQ(end.bricks().count(), 0) << "never split";
}

// Hardening, third round: bricks = 4x4x4 on a small volume made 21,504 brick tasks (hours of
// work), not counted in the queue. Bricks below 16^3 voxels are refused at once; a plan of
// more bricks than the server runs for one job, or that would overfill the queue, fails the
// job naming the limit, and nothing of it stays queued.
TEST_F(ServiceTest, ManyTinyBricksAreRefusedAndAJobsTasksAreBoundedAndCounted) {
  options_.limits.max_brick_tasks = 8;
  options_.limits.max_queued_jobs = 20;
  StartServer();
  const std::string vol = WritePhantom(options_.allowed_roots[0], "rock", 48, 21);
  v1::CreateJobRequest tiny;
  tiny.set_request_id("tiny");
  tiny.mutable_input()->set_volume_path(vol);
  tiny.set_bricks("4x4x4");
  auto refused = client_->CreateJob(tiny);
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(refused.status().message(), HasSubstr("bricks '4x4x4' holds 64 voxels"));
  // 3 x 3 x 3 bricks, over max_brick_tasks = 8.
  v1::CreateJobRequest many = tiny;
  many.set_request_id("many");
  many.set_bricks("16x16x16");
  many.set_no_cache(true);
  auto job = client_->CreateJob(many);
  ASSERT_TRUE(job.ok()) << job.status();
  v1::Job end = WaitFinished(job->name());
  EXPECT_EQ(end.state(), v1::FAILED);
  EXPECT_EQ(end.error().code(), static_cast<int>(absl::StatusCode::kInvalidArgument));
  EXPECT_THAT(end.error().message(), HasSubstr("27 bricks"));
  EXPECT_THAT(end.error().message(), HasSubstr("max_brick_tasks = 8"));
  EXPECT_EQ(end.bricks().count(), 0) << "never split";
}

TEST(CheckSplitTest, ASplitMayNotTakeTheQueueOfJobsAndTasksPastItsLimit) {
  std::unique_ptr<server::JobStore> store =
      server::OpenMemoryJobStore(server::NewMemoryJobTables());
  for (int k = 0; k < 14; ++k) {
    v1::Job job;
    job.set_tenant("default");
    job.set_state(v1::QUEUED);
    job.set_request_id(absl::StrCat("waiting-", k));
    bool created = false;
    ASSERT_TRUE(store->Create(job, absl::StrCat("k", k), &created).ok());
  }
  const server::SplitLimits limits{/*max_brick_tasks=*/8, /*max_queued_jobs=*/20};
  EXPECT_TRUE(server::CheckSplit(*store, limits, "jobs/x", 6).ok());
  const absl::Status full = server::CheckSplit(*store, limits, "jobs/x", 7);
  EXPECT_EQ(full.code(), absl::StatusCode::kResourceExhausted) << full;
  EXPECT_THAT(full.message(), HasSubstr("14 jobs and 0 brick tasks"));
  EXPECT_THAT(full.message(), HasSubstr("max_queued_jobs = 20"));
  const absl::Status many = server::CheckSplit(*store, limits, "jobs/x", 9);
  EXPECT_EQ(many.code(), absl::StatusCode::kInvalidArgument) << many;
  EXPECT_THAT(many.message(), HasSubstr("max_brick_tasks = 8"));
}

// The test is the worker (the server has none), speaking WorkerService as sheetmesh-worker
// does: the split, the leases of the bricks, their ends, the merge's lease.
class BrickProtocolTest : public ServiceTest {
 protected:
  void SetUp() override {
    ServiceTest::SetUp();
    options_.local_workers = false;
    options_.lease = absl::Milliseconds(600);
  }
  void Start() {
    StartServer();
    workers_ = v1::WorkerService::NewStub(grpc::CreateChannel(
        absl::StrCat("127.0.0.1:", server_->port()), grpc::InsecureChannelCredentials()));
    vol_ = WritePhantom(options_.allowed_roots[0], "rock", 16, 23);
    WriteRandomFile(dir_.File("plan.json"), 100, 1);
    WriteRandomFile(dir_.File("brick.bin"), 100, 2);
    auto plan = client_->Upload(dir_.File("plan.json"));
    auto brick = client_->Upload(dir_.File("brick.bin"));
    ASSERT_TRUE(plan.ok() && brick.ok());
    plan_.set_name("plan.json");
    *plan_.mutable_digest() = *plan;
    brick_.set_name("brick_0.bin");
    *brick_.mutable_digest() = *brick;
  }
  std::string Bricked(const std::string& request_id) {
    v1::CreateJobRequest r;
    r.set_request_id(request_id);
    r.mutable_input()->set_volume_path(vol_);
    r.set_bricks("16");
    r.set_no_cache(true);  // the test's merge writes no real outputs
    auto job = client_->CreateJob(r);
    EXPECT_TRUE(job.ok()) << job.status();
    return job.ok() ? job->name() : "";
  }
  v1::Job Lease(const std::string& worker) {
    v1::LeaseJobRequest req;
    req.set_worker(worker);
    v1::LeaseJobResponse resp;
    grpc::ClientContext ctx;
    const grpc::Status st = workers_->LeaseJob(&ctx, req, &resp);
    EXPECT_TRUE(st.ok()) << st.error_message();
    return resp.job();
  }
  grpc::Status Split(const std::string& job, const std::string& worker, int count,
                     v1::Job* out = nullptr) {
    v1::SplitJobRequest req;
    req.set_name(job);
    req.set_worker(worker);
    *req.mutable_plan() = plan_;
    req.set_count(count);
    v1::Job split;
    grpc::ClientContext ctx;
    grpc::Status st = workers_->SplitJob(&ctx, req, out ? out : &split);
    return st;
  }
  grpc::Status End(const std::string& job, const std::string& worker, v1::JobState state,
                   const std::string& error = "") {
    v1::FinishJobRequest req;
    req.set_name(job);
    req.set_worker(worker);
    req.set_state(state);
    if (state == v1::SUCCEEDED) *req.add_artifacts() = brick_;
    req.mutable_error()->set_code(state == v1::CANCELLED ? 1 : 13);
    req.mutable_error()->set_message(error);
    v1::Job done;
    grpc::ClientContext ctx;
    return workers_->FinishJob(&ctx, req, &done);
  }
  // A bricked job leased by a planner and split into `count` bricks: the split job.
  v1::Job Planned(const std::string& request_id, int count) {
    const std::string job = Bricked(request_id);
    EXPECT_EQ(Lease("planner").name(), job);
    v1::Job split;
    EXPECT_TRUE(Split(job, "planner", count, &split).ok());
    EXPECT_EQ(split.bricks().tasks_size(), count);
    return split;
  }
  v1::RenewLeaseResponse Renew(const std::string& job, const std::string& worker) {
    v1::RenewLeaseRequest req;
    req.set_name(job);
    req.set_worker(worker);
    v1::RenewLeaseResponse resp;
    grpc::ClientContext ctx;
    EXPECT_TRUE(workers_->RenewLease(&ctx, req, &resp).ok());
    return resp;
  }

  std::unique_ptr<v1::WorkerService::Stub> workers_;
  std::string vol_;
  v1::Artifact plan_, brick_;
};

TEST_F(BrickProtocolTest, AFailedBrickStopsItsSiblingsAndFailsTheJobNamingIt) {
  Start();
  const std::string job = Bricked("fails");
  const v1::Job leased = Lease("planner");
  ASSERT_EQ(leased.name(), job);
  EXPECT_EQ(leased.bricks().size(), "16");
  EXPECT_EQ(Split(job, "another", 3).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  const grpc::Status none = Split(job, "planner", 0);
  EXPECT_EQ(none.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(none.error_message(), HasSubstr("count 0"));
  v1::Job split;
  ASSERT_TRUE(Split(job, "planner", 3, &split).ok());
  ASSERT_EQ(split.bricks().tasks_size(), 3);
  EXPECT_EQ(Split(job, "planner", 3).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  auto seen = client_->GetJob(job);
  ASSERT_TRUE(seen.ok());
  EXPECT_EQ(seen->state(), v1::RUNNING) << "its bricks run";
  EXPECT_EQ(seen->progress().message(), "0 of 3 bricks done, 0 running");
  std::vector<std::string> tasks;
  for (const char* w : {"a", "b", "c"}) tasks.push_back(Lease(w).name());
  EXPECT_EQ(tasks,
            std::vector<std::string>(split.bricks().tasks().begin(), split.bricks().tasks().end()));
  EXPECT_EQ(client_->GetJob(job)->progress().message(), "0 of 3 bricks done, 3 running");
  ASSERT_TRUE(End(tasks[0], "a", v1::SUCCEEDED).ok());
  ASSERT_TRUE(End(tasks[1], "b", v1::FAILED, "the volume changed").ok());
  // The last brick is told to stop, and ends CANCELLED.
  const v1::RenewLeaseResponse stop = Renew(tasks[2], "c");
  EXPECT_TRUE(stop.stop() && stop.cancelled());
  ASSERT_TRUE(End(tasks[2], "c", v1::CANCELLED).ok());
  // No merge: the job failed at its lease, naming the brick and why.
  EXPECT_TRUE(Lease("merger").name().empty());
  auto end = client_->GetJob(job);
  ASSERT_TRUE(end.ok());
  EXPECT_EQ(end->state(), v1::FAILED);
  EXPECT_THAT(end->error().message(),
              HasSubstr("brick 1 of 3 (" + tasks[1] + ") failed: the volume changed"));
}

TEST_F(BrickProtocolTest, ALostBrickRunsAgainAndCancelReachesEveryBrick) {
  Start();
  v1::Job split = Planned("lost", 2);
  const std::string job = split.name();
  ASSERT_FALSE(HasFailure());
  const std::string t0 = Lease("a").name(), t1 = Lease("b").name();
  ASSERT_TRUE(End(t0, "a", v1::SUCCEEDED).ok());
  // Worker b is killed: its lease runs out, the brick is queued again and runs once more.
  std::string again;
  for (int i = 0; i < 100 && again.empty(); ++i) {
    absl::SleepFor(absl::Milliseconds(100));
    again = Lease("b2").name();
  }
  ASSERT_EQ(again, t1);
  EXPECT_EQ(client_->GetJob(t1)->attempts(), 2);
  EXPECT_EQ(End(t1, "b", v1::SUCCEEDED).error_code(), grpc::StatusCode::FAILED_PRECONDITION)
      << "the lost worker's late result does not count";
  ASSERT_TRUE(End(t1, "b2", v1::SUCCEEDED).ok());
  const v1::Job merge = Lease("merger");
  ASSERT_EQ(merge.name(), job);
  ASSERT_EQ(merge.bricks().outputs_size(), 2) << "each brick's output, in order";
  EXPECT_EQ(merge.bricks().outputs(1).digest().hash(), brick_.digest().hash());
  ASSERT_TRUE(End(job, "merger", v1::SUCCEEDED).ok());

  // A second job, cancelled while one brick runs and one waits.
  split = Planned("cancelled", 2);
  const std::string job2 = split.name();
  ASSERT_FALSE(HasFailure());
  const std::string running = Lease("a").name();
  v1::CancelJobRequest cr;
  cr.set_name(job2);
  v1::Job cancelled;
  ASSERT_TRUE(client_->jobs()->CancelJob(client_->Context().get(), cr, &cancelled).ok());
  EXPECT_EQ(cancelled.state(), v1::CANCELLED);
  EXPECT_EQ(client_->GetJob(split.bricks().tasks(1))->state(), v1::CANCELLED) << "queued";
  const v1::RenewLeaseResponse stop = Renew(running, "a");
  EXPECT_TRUE(stop.stop() && stop.cancelled()) << "running";
  ASSERT_TRUE(End(running, "a", v1::CANCELLED).ok());
  EXPECT_TRUE(Lease("idle").name().empty()) << "nothing left to run";
  EXPECT_EQ(client_->GetJob(job2)->state(), v1::CANCELLED);
}

TEST_F(BrickProtocolTest, ABrickLostTooOftenStopsItsSiblingsAndFailsTheJobNamingIt) {
  options_.max_attempts = 1;
  Start();
  const v1::Job split = Planned("lost for good", 3);
  const std::string job = split.name();
  ASSERT_FALSE(HasFailure());
  const std::string t0 = Lease("a").name(), t1 = Lease("b").name();
  // Worker a is killed; b renews its lease. With max_attempts 1 a's brick fails for good
  // when its lease runs out, and the server tells b's brick to stop, and the queued one.
  v1::RenewLeaseResponse renewed;
  for (int i = 0; i < 100 && !renewed.stop(); ++i) {
    absl::SleepFor(absl::Milliseconds(100));
    renewed = Renew(t1, "b");
  }
  EXPECT_TRUE(renewed.stop() && renewed.cancelled()) << "the running sibling is stopped";
  const auto lost = client_->GetJob(t0);
  ASSERT_TRUE(lost.ok());
  EXPECT_EQ(lost->state(), v1::FAILED);
  EXPECT_THAT(lost->error().message(), HasSubstr("max_attempts = 1"));
  EXPECT_EQ(client_->GetJob(split.bricks().tasks(2))->state(), v1::CANCELLED) << "queued";
  ASSERT_TRUE(End(t1, "b", v1::CANCELLED).ok());
  EXPECT_TRUE(Lease("merger").name().empty()) << "no merge";
  auto end = client_->GetJob(job);
  ASSERT_TRUE(end.ok());
  EXPECT_EQ(end->state(), v1::FAILED);
  EXPECT_THAT(end->error().message(), HasSubstr("brick 0 of 3 (" + t0 + ") failed: its worker"));
}

}  // namespace
}  // namespace sheetmesh::testing
