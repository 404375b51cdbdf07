// The job service over real gRPC on loopback: idempotent creation, watching every stage,
// cancelling, the result cache, listing and deleting.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <thread>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/time/clock.h"
#include "common/file_util.h"
#include "nlohmann/json.hpp"
#include "server/blob_store.h"
#include "tests/server/service_fixture.h"

namespace sheetmesh::testing {
namespace {

using ::testing::HasSubstr;

// ---------------------------------------------------------------------------------------
// Jobs

TEST_F(ServiceTest, SameRequestIdGivesOneJob) {
  StartServer();
  const std::string vol = WritePhantom(dir_.path(), "rock", 48, 1);
  auto d = client_->Upload(vol);
  ASSERT_TRUE(d.ok());
  v1::CreateJobRequest r = UploadRequest(*d, std::filesystem::path(vol).filename(), "req-1");
  auto a = client_->CreateJob(r);
  auto b = client_->CreateJob(r);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->name(), b->name());
  v1::ListJobsRequest list;
  auto all = client_->ListJobs(list);
  ASSERT_TRUE(all.ok());
  EXPECT_EQ(all->jobs_size(), 1);
  EXPECT_EQ(WaitFinished(a->name()).state(), v1::SUCCEEDED);
}

TEST_F(ServiceTest, WatchSeesEveryStageInOrderAndTheResult) {
  // One worker, held by a long job until the watch has begun on the queued job: then the
  // watch sees the job from before its first stage, however busy the machine is.
  options_.workers = 1;
  StartServer();
  const std::string slow = WritePhantom(options_.allowed_roots[0], "slow", 160, 3);
  v1::CreateJobRequest hold;
  hold.set_request_id("hold-the-worker");
  hold.mutable_input()->set_volume_path(slow);
  hold.mutable_parameters()->set_extract(true);
  auto blocker = client_->CreateJob(hold);
  ASSERT_TRUE(blocker.ok()) << blocker.status();
  const std::string vol = WritePhantom(dir_.path(), "rock", 64, 2);
  auto d = client_->Upload(vol);
  ASSERT_TRUE(d.ok());
  v1::CreateJobRequest r = UploadRequest(*d, std::filesystem::path(vol).filename(), "watch-1");
  r.mutable_parameters()->set_extract(true);
  auto job = client_->CreateJob(r);
  ASSERT_TRUE(job.ok()) << job.status();
  std::vector<int> stages;
  std::vector<std::string> names;
  int count = 0;
  bool released = false;
  auto final_job = client_->Watch(job->name(), [&](const v1::WatchJobResponse& m) {
    if (!released) {
      EXPECT_EQ(m.job().state(), v1::QUEUED) << "the worker was not held";
      released = client_->CancelJob(blocker->name()).ok();
    }
    // Stage 0: leased, not begun.
    if (m.job().state() != v1::RUNNING || m.job().progress().stage_index() == 0) return;
    const int i = m.job().progress().stage_index();
    if (stages.empty() || stages.back() != i) {
      stages.push_back(i);
      names.push_back(m.job().progress().stage());
    }
    count = m.job().progress().stage_count();
  });
  ASSERT_TRUE(final_job.ok()) << final_job.status();
  EXPECT_EQ(final_job->state(), v1::SUCCEEDED) << final_job->error().message();
  // Every stage, once, in order: 1, 2, ..., count.
  ASSERT_GT(count, 3);
  std::vector<int> expected(count);
  for (int i = 0; i < count; ++i) expected[i] = i + 1;
  EXPECT_EQ(stages, expected) << absl::StrJoin(names, ",");
  EXPECT_EQ(names.front(), "read");
  EXPECT_EQ(names.back(), "write") << absl::StrJoin(names, ",");
  // Artifacts with digests and media types, readable.
  std::map<std::string, v1::Artifact> by_name;
  for (const auto& a : final_job->artifacts()) by_name[a.name()] = a;
  ASSERT_TRUE(by_name.count("report.json"));
  ASSERT_TRUE(by_name.count("surface.ply"));
  EXPECT_EQ(by_name["report.json"].media_type(), "application/json");
  EXPECT_EQ(by_name["surface.ply"].media_type(), "model/x-ply");
  ASSERT_TRUE(client_->Download(by_name["report.json"].digest(), dir_.File("report.json")).ok());
  auto report = nlohmann::json::parse(Slurp(dir_.File("report.json")));
  EXPECT_GT(report["similarity"]["similarity"].get<double>(), 0.3);
  EXPECT_EQ(final_job->attempts(), 1);
  EXPECT_TRUE(final_job->has_end_time());
}

TEST_F(ServiceTest, LateWatcherGetsTheCurrentSnapshot) {
  StartServer();
  const std::string vol = WritePhantom(options_.allowed_roots[0], "slow", 256, 3);
  v1::CreateJobRequest r;
  r.set_request_id("late-1");
  r.mutable_input()->set_volume_path(vol);
  r.mutable_parameters()->set_extract(true);
  auto job = client_->CreateJob(r);
  ASSERT_TRUE(job.ok()) << job.status();
  const v1::Job running = WaitRunning(*client_, job->name(), 2);
  ASSERT_EQ(running.state(), v1::RUNNING);
  // A watcher joining now is told at once where the job is.
  auto ctx = client_->Context();
  v1::WatchJobRequest wr;
  wr.set_name(job->name());
  auto reader = client_->jobs()->WatchJob(ctx.get(), wr);
  v1::WatchJobResponse first;
  ASSERT_TRUE(reader->Read(&first));
  EXPECT_EQ(first.job().state(), v1::RUNNING);
  EXPECT_GE(first.job().progress().stage_index(), 2);
  EXPECT_FALSE(first.job().progress().stage().empty());
  ctx->TryCancel();
  reader->Finish();
  ASSERT_TRUE(client_->CancelJob(job->name()).ok());
  EXPECT_EQ(WaitFinished(job->name()).state(), v1::CANCELLED);
  // A watcher of a finished job gets that job and the stream ends.
  int messages = 0;
  auto done = client_->Watch(job->name(), [&](const v1::WatchJobResponse&) { ++messages; });
  ASSERT_TRUE(done.ok());
  EXPECT_EQ(messages, 1);
  EXPECT_EQ(done->state(), v1::CANCELLED);
}

TEST_F(ServiceTest, CancelStopsTheRunningStageAndFreesTheWorker) {
  options_.workers = 1;
  StartServer();
  const std::string vol = WritePhantom(options_.allowed_roots[0], "slow", 288, 4);
  v1::CreateJobRequest r;
  r.set_request_id("cancel-1");
  r.mutable_input()->set_volume_path(vol);
  r.mutable_parameters()->set_extract(true);
  auto job = client_->CreateJob(r);
  ASSERT_TRUE(job.ok()) << job.status();
  // Into the extraction, the long stage.
  v1::Job running = WaitRunning(*client_, job->name(), 2);
  ASSERT_EQ(running.state(), v1::RUNNING);
  // Inside the stage, not at its start: its progress moved.
  const absl::Time deadline = absl::Now() + absl::Seconds(60);
  while (running.state() == v1::RUNNING && running.progress().fraction() == 0 &&
         absl::Now() < deadline) {
    absl::SleepFor(absl::Milliseconds(20));
    auto again = client_->GetJob(job->name());
    ASSERT_TRUE(again.ok());
    running = *again;
  }
  ASSERT_EQ(running.state(), v1::RUNNING);
  auto cancelled = client_->CancelJob(job->name());
  ASSERT_TRUE(cancelled.ok()) << cancelled.status();
  const v1::Job end = WaitFinished(job->name());
  EXPECT_EQ(end.state(), v1::CANCELLED);
  EXPECT_EQ(end.error().code(), static_cast<int>(absl::StatusCode::kCancelled));
  // The cancel reached the running stage: the run stopped there, before its results (how
  // fast is measured in bench/service_bench.py, not asserted here).
  EXPECT_TRUE(end.artifacts().empty()) << "the job ran to its end";
  // The only worker takes the next job.
  const std::string small = WritePhantom(options_.allowed_roots[0], "small", 40, 5);
  v1::CreateJobRequest next;
  next.set_request_id("after-cancel");
  next.mutable_input()->set_volume_path(small);
  auto j2 = client_->CreateJob(next);
  ASSERT_TRUE(j2.ok());
  EXPECT_EQ(WaitFinished(j2->name()).state(), v1::SUCCEEDED);
  // Cancelling a finished job changes nothing.
  auto again = client_->CancelJob(j2->name());
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->state(), v1::SUCCEEDED);
}

TEST_F(ServiceTest, CancelQueuedJobEndsItAtOnce) {
  options_.workers = 1;
  StartServer();
  const std::string slow = WritePhantom(options_.allowed_roots[0], "slow", 256, 6);
  v1::CreateJobRequest r;
  r.set_request_id("busy");
  r.mutable_input()->set_volume_path(slow);
  r.mutable_parameters()->set_extract(true);
  auto busy = client_->CreateJob(r);
  ASSERT_TRUE(busy.ok());
  r.set_request_id("waiting");
  r.set_no_cache(true);
  auto waiting = client_->CreateJob(r);
  ASSERT_TRUE(waiting.ok());
  auto c = client_->CancelJob(waiting->name());
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->state(), v1::CANCELLED);
  ASSERT_TRUE(client_->CancelJob(busy->name()).ok());
  EXPECT_EQ(WaitFinished(busy->name()).state(), v1::CANCELLED);
}

TEST_F(ServiceTest, DroppedWatchDoesNotCancel) {
  StartServer();
  const std::string vol = WritePhantom(options_.allowed_roots[0], "mid", 160, 7);
  v1::CreateJobRequest r;
  r.set_request_id("drop-1");
  r.mutable_input()->set_volume_path(vol);
  r.mutable_parameters()->set_extract(true);
  auto job = client_->CreateJob(r);
  ASSERT_TRUE(job.ok());
  {
    auto ctx = client_->Context();
    v1::WatchJobRequest wr;
    wr.set_name(job->name());
    auto reader = client_->jobs()->WatchJob(ctx.get(), wr);
    v1::WatchJobResponse m;
    ASSERT_TRUE(reader->Read(&m));
    ctx->TryCancel();  // the watcher goes away mid-job
    reader->Finish();
  }
  const v1::Job end = WaitFinished(job->name());
  EXPECT_EQ(end.state(), v1::SUCCEEDED) << end.error().message();
}

TEST_F(ServiceTest, IdenticalWorkIsAnsweredFromTheCache) {
  StartServer();
  const std::string vol = WritePhantom(dir_.path(), "rock", 48, 8);
  auto d = client_->Upload(vol);
  ASSERT_TRUE(d.ok());
  const std::string file = std::filesystem::path(vol).filename();
  auto first = client_->CreateJob(UploadRequest(*d, file, "c-1"));
  ASSERT_TRUE(first.ok());
  const v1::Job done = WaitFinished(first->name());
  ASSERT_EQ(done.state(), v1::SUCCEEDED);
  auto second = client_->CreateJob(UploadRequest(*d, file, "c-2"));
  ASSERT_TRUE(second.ok());
  EXPECT_EQ(second->state(), v1::SUCCEEDED);
  EXPECT_EQ(second->cached_from(), first->name());
  ASSERT_EQ(second->artifacts_size(), done.artifacts_size());
  for (int i = 0; i < done.artifacts_size(); ++i) {
    EXPECT_EQ(second->artifacts(i).digest().hash(), done.artifacts(i).digest().hash());
  }
  // Other parameters, or no_cache, run again.
  v1::CreateJobRequest other = UploadRequest(*d, file, "c-3");
  other.mutable_parameters()->set_r(5);
  auto third = client_->CreateJob(other);
  ASSERT_TRUE(third.ok());
  EXPECT_TRUE(third->cached_from().empty());
  v1::CreateJobRequest fresh = UploadRequest(*d, file, "c-4");
  fresh.set_no_cache(true);
  auto fourth = client_->CreateJob(fresh);
  ASSERT_TRUE(fourth.ok());
  EXPECT_TRUE(fourth->cached_from().empty());
  EXPECT_EQ(WaitFinished(third->name()).state(), v1::SUCCEEDED);
  EXPECT_EQ(WaitFinished(fourth->name()).state(), v1::SUCCEEDED);
}

TEST_F(ServiceTest, AFailedVolumeStageFailsTheJobWithWhatItKept) {
  // Once a failed job had no artifacts, though its surface, score and previews were done.
  StartServer();
  const std::string vol = WritePhantom(dir_.path(), "rock", 48, 8);
  auto d = client_->Upload(vol);
  ASSERT_TRUE(d.ok());
  v1::CreateJobRequest r = UploadRequest(*d, std::filesystem::path(vol).filename(), "kept");
  r.mutable_parameters()->set_volume_mesh(true);
  r.mutable_parameters()->set_max_tetrahedra(10);  // below what any volume mesh needs
  auto job = client_->CreateJob(r);
  ASSERT_TRUE(job.ok()) << job.status();
  const v1::Job done = WaitFinished(job->name());
  ASSERT_EQ(done.state(), v1::FAILED);
  EXPECT_THAT(done.error().message(), HasSubstr("max_tetrahedra = 10"));
  EXPECT_THAT(done.error().message(), HasSubstr("kept as artifacts: surface.ply"));
  ASSERT_FALSE(options_.data_dir.empty());
  EXPECT_THAT(done.error().message(), ::testing::Not(HasSubstr(options_.data_dir)));
  std::set<std::string> names;
  for (const v1::Artifact& a : done.artifacts()) names.insert(a.name());
  EXPECT_TRUE(names.count("surface.ply") && names.count("report.json")) << done.DebugString();
  EXPECT_FALSE(names.count("volume.vtu"));
  for (const v1::Artifact& a : done.artifacts()) {
    if (a.name() != "report.json") continue;
    ASSERT_TRUE(client_->Download(a.digest(), dir_.File("kept_report.json")).ok());
    auto text = ReadFileToString(dir_.File("kept_report.json"));
    ASSERT_TRUE(text.ok());
    EXPECT_EQ(nlohmann::json::parse(*text)["failed"]["stage"], "volume");
  }
  // A failed job answers no identical request from the cache.
  r.set_request_id("kept-again");
  auto again = client_->CreateJob(r);
  ASSERT_TRUE(again.ok());
  EXPECT_TRUE(again->cached_from().empty());
  EXPECT_EQ(WaitFinished(again->name()).state(), v1::FAILED);
}

// Flow and the split mesh through the service: the job's parameters turn them on, the watch
// sees the flow stage, the report carries the tensor and the split, and the fields, the split
// decks and the tensor's chart come back as artifacts.
TEST_F(ServiceTest, AFlowJobReturnsTheTensorTheFieldsAndTheSplitMesh) {
  StartServer();
  const std::string vol = WritePhantom(dir_.path(), "rock", 48, 8);
  auto d = client_->Upload(vol);
  ASSERT_TRUE(d.ok());
  v1::CreateJobRequest r = UploadRequest(*d, std::filesystem::path(vol).filename(), "flow");
  r.mutable_input()->mutable_format()->set_unit("um");
  for (int k = 0; k < 3; ++k) r.mutable_input()->mutable_format()->add_spacing(5);
  r.mutable_parameters()->set_flow(true);
  r.mutable_parameters()->set_output_split(true);
  r.mutable_parameters()->set_permeability_matrix(1e-17);
  auto job = client_->CreateJob(r);
  ASSERT_TRUE(job.ok()) << job.status();
  std::vector<std::string> stages;
  auto done = client_->Watch(job->name(), [&](const v1::WatchJobResponse& m) {
    const std::string& stage = m.job().progress().stage();
    if (m.job().state() == v1::RUNNING && (stages.empty() || stages.back() != stage)) {
      stages.push_back(stage);
    }
  });
  ASSERT_TRUE(done.ok()) << done.status();
  ASSERT_EQ(done->state(), v1::SUCCEEDED) << done->error().message();
  EXPECT_NE(std::find(stages.begin(), stages.end(), "flow"), stages.end())
      << absl::StrJoin(stages, ",");
  std::map<std::string, v1::Artifact> by_name;
  for (const auto& a : done->artifacts()) by_name[a.name()] = a;
  for (const char* f : {"volume.vtu", "volume_split.inp", "volume_split_ccx.inp",
                        "volume_split.exo", "preview_permeability.png"}) {
    EXPECT_TRUE(by_name.count(f)) << f;
  }
  EXPECT_EQ(by_name["volume_split.exo"].media_type(), "application/x-netcdf");
  ASSERT_TRUE(client_->Download(by_name["report.json"].digest(), dir_.File("flow.json")).ok());
  const nlohmann::json report = nlohmann::json::parse(*ReadFileToString(dir_.File("flow.json")));
  EXPECT_GE(report["flow"]["permeability_m2"][0][0].get<double>(), 0.99e-17);
  EXPECT_GT(report["volume_split"]["interfaces"].get<int>(), 0);
  ASSERT_TRUE(client_->Download(by_name["volume.vtu"].digest(), dir_.File("v.vtu")).ok());
  EXPECT_THAT(*ReadFileToString(dir_.File("v.vtu")), HasSubstr("Name=\"pressure_x\""));
}

TEST_F(ServiceTest, ListPagesDeleteAndGet) {
  StartServer();
  const std::string vol = WritePhantom(dir_.path(), "rock", 40, 9);
  auto d = client_->Upload(vol);
  ASSERT_TRUE(d.ok());
  std::vector<std::string> created;
  for (int i = 0; i < 5; ++i) {
    v1::CreateJobRequest r =
        UploadRequest(*d, std::filesystem::path(vol).filename(), absl::StrCat("p-", i));
    r.set_no_cache(true);
    auto j = client_->CreateJob(r);
    ASSERT_TRUE(j.ok());
    created.push_back(j->name());
  }
  for (const auto& n : created) ASSERT_EQ(WaitFinished(n).state(), v1::SUCCEEDED);
  std::vector<std::string> listed;
  v1::ListJobsRequest req;
  req.set_page_size(2);
  int pages = 0;
  do {
    auto resp = client_->ListJobs(req);
    ASSERT_TRUE(resp.ok()) << resp.status();
    EXPECT_LE(resp->jobs_size(), 2);
    for (const auto& j : resp->jobs()) listed.push_back(j.name());
    req.set_page_token(resp->next_page_token());
    ++pages;
  } while (!req.page_token().empty() && pages < 10);
  EXPECT_EQ(pages, 3);
  std::vector<std::string> newest_first(created.rbegin(), created.rend());
  EXPECT_EQ(listed, newest_first);
  // By state.
  v1::ListJobsRequest queued;
  queued.set_state(v1::QUEUED);
  auto none = client_->ListJobs(queued);
  ASSERT_TRUE(none.ok());
  EXPECT_EQ(none->jobs_size(), 0);
  // A bad page token is the caller's error.
  v1::ListJobsRequest bad;
  bad.set_page_token("not-a-token");
  EXPECT_EQ(client_->ListJobs(bad).status().code(), absl::StatusCode::kInvalidArgument);
  // Delete.
  ASSERT_TRUE(client_->DeleteJob(created[0]).ok());
  EXPECT_EQ(client_->GetJob(created[0]).status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(client_->GetJob("jobs/nope").status().code(), absl::StatusCode::kNotFound);
}

TEST_F(ServiceTest, DeletingAnUnfinishedJobIsRefused) {
  options_.workers = 1;
  StartServer();
  const std::string slow = WritePhantom(options_.allowed_roots[0], "slow", 256, 10);
  v1::CreateJobRequest r;
  r.set_request_id("del");
  r.mutable_input()->set_volume_path(slow);
  r.mutable_parameters()->set_extract(true);
  auto job = client_->CreateJob(r);
  ASSERT_TRUE(job.ok());
  absl::Status st = client_->DeleteJob(job->name());
  EXPECT_EQ(st.code(), absl::StatusCode::kFailedPrecondition) << st;
  ASSERT_TRUE(client_->CancelJob(job->name()).ok());
  WaitFinished(job->name());
  EXPECT_TRUE(client_->DeleteJob(job->name()).ok());
}

}  // namespace
}  // namespace sheetmesh::testing
