// The service over real gRPC on loopback: uploads, jobs, watching, cancellation, bad
// input, limits and load, against an embedded server with its own data folder.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/time/clock.h"
#include "nlohmann/json.hpp"
#include "server/blob_store.h"
#include "tests/server/service_fixture.h"
#include "common/file_util.h"

namespace sheetmesh::testing {
namespace {

using ::testing::HasSubstr;

std::string WriteRandomFile(const std::string& path, int64_t size, uint32_t seed) {
  std::mt19937 gen(seed);
  std::string bytes(size, '\0');
  for (auto& c : bytes) c = static_cast<char>(gen());
  std::ofstream(path, std::ios::binary).write(bytes.data(), bytes.size());
  return bytes;
}

std::string Slurp(const std::string& path) {
  auto s = ReadFileToString(path);
  EXPECT_TRUE(s.ok()) << s.status();
  return s.ok() ? *s : "";
}

std::vector<v1::Digest> Missing(client::SheetmeshClient& c, const v1::Digest& d) {
  v1::FindMissingBlobsRequest req;
  *req.add_digests() = d;
  v1::FindMissingBlobsResponse resp;
  grpc::Status st = c.blobs()->FindMissingBlobs(c.Context().get(), req, &resp);
  EXPECT_TRUE(st.ok()) << st.error_message();
  return {resp.missing().begin(), resp.missing().end()};
}

int64_t ProcessRssBytes() {
  std::ifstream f("/proc/self/statm");
  int64_t pages = 0, resident = 0;
  f >> pages >> resident;
  return resident * ::sysconf(_SC_PAGESIZE);
}

// Polls until the job is RUNNING at stage `stage` or later (or finished); returns the job.
v1::Job WaitRunning(client::SheetmeshClient& c, const std::string& name, int min_stage) {
  const absl::Time deadline = absl::Now() + absl::Seconds(60);
  for (;;) {
    auto job = c.GetJob(name);
    EXPECT_TRUE(job.ok()) << job.status();
    if (!job.ok()) return {};
    if (job->state() != v1::QUEUED &&
        (job->state() != v1::RUNNING || job->progress().stage_index() >= min_stage)) {
      return *job;
    }
    if (absl::Now() > deadline) {
      ADD_FAILURE() << name << " did not start";
      return *job;
    }
    absl::SleepFor(absl::Milliseconds(20));
  }
}

// ---------------------------------------------------------------------------------------
// Uploads

TEST_F(ServiceTest, UploadWholeThenFindMissingAndRangedRead) {
  StartServer();
  const std::string path = dir_.File("blob.bin");
  const std::string bytes = WriteRandomFile(path, 3 * (1 << 20) + 12345, 7);
  auto digest = server::DigestOfFile(path);
  ASSERT_TRUE(digest.ok());
  EXPECT_EQ(Missing(*client_, *digest).size(), 1u);
  auto up = client_->Upload(path);
  ASSERT_TRUE(up.ok()) << up.status();
  EXPECT_EQ(up->hash(), digest->hash());
  EXPECT_TRUE(Missing(*client_, *digest).empty());
  // The whole blob back.
  ASSERT_TRUE(client_->Download(*digest, dir_.File("back.bin")).ok());
  EXPECT_EQ(Slurp(dir_.File("back.bin")), bytes);
  // A range across a piece boundary.
  v1::ReadRequest req;
  *req.mutable_digest() = *digest;
  req.set_read_offset((1 << 20) - 100);
  req.set_read_limit(5000);
  auto ctx = client_->Context();
  auto reader = client_->blobs()->Read(ctx.get(), req);
  std::string got;
  v1::ReadResponse resp;
  while (reader->Read(&resp)) got += resp.data();
  ASSERT_TRUE(reader->Finish().ok());
  EXPECT_EQ(got, bytes.substr((1 << 20) - 100, 5000));
  // Uploading again sends nothing and answers the same digest.
  int64_t reported = -1;
  auto again = client_->Upload(path, [&](int64_t sent, int64_t) { reported = sent; });
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(reported, digest->size_bytes());
}

TEST_F(ServiceTest, UploadResumesAfterBrokenStream) {
  StartServer();
  const std::string path = dir_.File("big.bin");
  const std::string bytes = WriteRandomFile(path, 6 * (1 << 20) + 77, 8);
  auto digest = server::DigestOfFile(path);
  ASSERT_TRUE(digest.ok());
  // The client library names the upload by the content: break a stream of that name
  // after three pieces.
  const std::string resource = absl::StrCat("uploads/u", digest->hash().substr(0, 32), "/blobs/",
                                            digest->hash(), "/", digest->size_bytes());
  {
    auto ctx = client_->Context();
    v1::WriteResponse resp;
    auto writer = client_->blobs()->Write(ctx.get(), &resp);
    for (int i = 0; i < 3; ++i) {
      v1::WriteRequest req;
      if (i == 0) req.set_resource_name(resource);
      req.set_write_offset(int64_t{i} << 20);
      req.set_data(bytes.substr(static_cast<size_t>(i) << 20, size_t{1} << 20));
      ASSERT_TRUE(writer->Write(req));
    }
    // Let the pieces arrive, then break the stream.
    absl::SleepFor(absl::Milliseconds(300));
    ctx->TryCancel();
    EXPECT_FALSE(writer->Finish().ok());
  }
  // The broken upload is durable up to what arrived, and no blob is visible.
  v1::QueryWriteStatusRequest q;
  q.set_resource_name(resource);
  v1::QueryWriteStatusResponse qs;
  const absl::Time deadline = absl::Now() + absl::Seconds(10);
  do {
    ASSERT_TRUE(client_->blobs()->QueryWriteStatus(client_->Context().get(), q, &qs).ok());
    if (qs.committed_size() == 3 << 20) break;
    absl::SleepFor(absl::Milliseconds(50));
  } while (absl::Now() < deadline);
  EXPECT_EQ(qs.committed_size(), 3 << 20);
  EXPECT_FALSE(qs.complete());
  EXPECT_EQ(Missing(*client_, *digest).size(), 1u);
  // The client resumes where the server stopped: its first report is past that point.
  int64_t first_report = -1;
  auto up = client_->Upload(path, [&](int64_t sent, int64_t) {
    if (first_report < 0) first_report = sent;
  });
  ASSERT_TRUE(up.ok()) << up.status();
  EXPECT_EQ(first_report, 4 << 20);
  ASSERT_TRUE(client_->Download(*digest, dir_.File("back.bin")).ok());
  EXPECT_EQ(Slurp(dir_.File("back.bin")), bytes);
}

TEST_F(ServiceTest, UploadWithWrongDigestIsRefusedAndLeavesNoBlob) {
  StartServer();
  const std::string bytes = WriteRandomFile(dir_.File("a.bin"), 100000, 9);
  WriteRandomFile(dir_.File("b.bin"), 100000, 10);
  auto claimed = server::DigestOfFile(dir_.File("b.bin"));  // the digest of other bytes
  ASSERT_TRUE(claimed.ok());
  const std::string resource =
      absl::StrCat("uploads/liar/blobs/", claimed->hash(), "/", claimed->size_bytes());
  auto ctx = client_->Context();
  v1::WriteResponse resp;
  auto writer = client_->blobs()->Write(ctx.get(), &resp);
  v1::WriteRequest req;
  req.set_resource_name(resource);
  req.set_data(bytes);
  req.set_finish_write(true);
  writer->Write(req);
  writer->WritesDone();
  grpc::Status st = writer->Finish();
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(st.error_message(), HasSubstr(claimed->hash()));
  EXPECT_EQ(Missing(*client_, *claimed).size(), 1u);
  // Nothing of it is left in the store: not a blob, not a part file.
  for (const auto& e :
       std::filesystem::recursive_directory_iterator(options_.data_dir + "/blobs")) {
    EXPECT_FALSE(e.is_regular_file()) << e.path();
  }
}

TEST_F(ServiceTest, UploadLargerThanTheLimitIsResourceExhausted) {
  options_.limits.max_blob_bytes = 1000;
  StartServer();
  WriteRandomFile(dir_.File("a.bin"), 5000, 11);
  auto up = client_->Upload(dir_.File("a.bin"));
  ASSERT_FALSE(up.ok());
  EXPECT_EQ(up.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(up.status().message(), HasSubstr("max_blob_bytes"));
}

TEST_F(ServiceTest, MalformedResourceNameIsInvalidArgument) {
  StartServer();
  auto ctx = client_->Context();
  v1::WriteResponse resp;
  auto writer = client_->blobs()->Write(ctx.get(), &resp);
  v1::WriteRequest req;
  req.set_resource_name("uploads/x/../../etc/blobs/abc/3");
  req.set_data("abc");
  writer->Write(req);
  writer->WritesDone();
  grpc::Status st = writer->Finish();
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(st.error_message(), HasSubstr("resource_name"));
}

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
  StartServer();
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
  auto final_job = client_->Watch(job->name(), [&](const v1::WatchJobResponse& m) {
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
  EXPECT_EQ(names.back(), "write");
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
  const v1::Job running = WaitRunning(*client_, job->name(), 2);
  ASSERT_EQ(running.state(), v1::RUNNING);
  absl::SleepFor(absl::Milliseconds(500));
  const absl::Time asked = absl::Now();
  auto cancelled = client_->CancelJob(job->name());
  ASSERT_TRUE(cancelled.ok()) << cancelled.status();
  const v1::Job end = WaitFinished(job->name());
  const absl::Duration took = absl::Now() - asked;
  EXPECT_EQ(end.state(), v1::CANCELLED);
  EXPECT_EQ(end.error().code(), static_cast<int>(absl::StatusCode::kCancelled));
  EXPECT_LT(took, absl::Seconds(2))
      << "stopped after " << took << " in stage " << running.progress().stage();
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

// ---------------------------------------------------------------------------------------
// Bad input

TEST_F(ServiceTest, ReferencesOutsideTheAllowedRootsArePermissionDenied) {
  StartServer();
  const std::string outside = WritePhantom(dir_.path(), "outside", 32, 11);
  const std::string inside = WritePhantom(options_.allowed_roots[0], "inside", 32, 12);
  std::filesystem::create_symlink(outside, options_.allowed_roots[0] + "/escape_32x32x32_u8.raw");
  const std::vector<std::string> refused = {
      outside,
      options_.allowed_roots[0] + "/../outside_32x32x32_u8.raw",
      options_.allowed_roots[0] + "/escape_32x32x32_u8.raw",
      "/etc/passwd",
  };
  for (const std::string& path : refused) {
    v1::CreateJobRequest r;
    r.set_request_id(absl::StrCat("ref-", path));
    r.mutable_input()->set_volume_path(path);
    auto job = client_->CreateJob(r);
    EXPECT_EQ(job.status().code(), absl::StatusCode::kPermissionDenied)
        << path << ": " << job.status();
    v1::InspectVolumeRequest ir;
    ir.set_path(path);
    v1::InspectVolumeResponse iresp;
    EXPECT_EQ(client_->volumes()->InspectVolume(client_->Context().get(), ir, &iresp).error_code(),
              grpc::StatusCode::PERMISSION_DENIED);
  }
  // Inside the root: inspected, imported and meshed.
  v1::InspectVolumeRequest ir;
  ir.set_path(inside);
  v1::InspectVolumeResponse iresp;
  ASSERT_TRUE(client_->volumes()->InspectVolume(client_->Context().get(), ir, &iresp).ok());
  EXPECT_THAT(iresp.dims(), ::testing::ElementsAre(32, 32, 32));
  EXPECT_EQ(iresp.dtype(), "uint8");
  v1::ImportVolumeRequest imp;
  imp.set_path(inside);
  v1::ImportVolumeResponse impr;
  ASSERT_TRUE(client_->volumes()->ImportVolume(client_->Context().get(), imp, &impr).ok());
  EXPECT_EQ(impr.digest().size_bytes(), 32 * 32 * 32);
  EXPECT_TRUE(Missing(*client_, impr.digest()).empty());
  v1::CreateJobRequest r;
  r.set_request_id("ref-ok");
  r.mutable_input()->set_volume_path(inside);
  auto job = client_->CreateJob(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(WaitFinished(job->name()).state(), v1::SUCCEEDED);
  // A missing file under the root is NOT_FOUND.
  r.set_request_id("ref-missing");
  r.mutable_input()->set_volume_path(options_.allowed_roots[0] + "/none_8x8x8_u8.raw");
  EXPECT_EQ(client_->CreateJob(r).status().code(), absl::StatusCode::kNotFound);
}

TEST_F(ServiceTest, BadParametersAreInvalidArgumentNamingTheField) {
  StartServer();
  const std::string vol = WritePhantom(options_.allowed_roots[0], "rock", 32, 13);
  struct Case {
    std::function<void(v1::PipelineParameters*)> set;
    std::string field;
  };
  const std::vector<Case> cases = {
      {[](v1::PipelineParameters* p) { p->set_r(-3); }, "parameters.r = -3.0 must be a number in"},
      {[](v1::PipelineParameters* p) { p->set_separate_d_ang(200); },
       "parameters.separate_D_ang = 200.0"},
      {[](v1::PipelineParameters* p) { p->set_surface_method("magic"); },
       "parameters.surface_method = \"magic\" must be one of extended, paper"},
      {[](v1::PipelineParameters* p) { p->set_tet_min_dihedral(80); },
       "parameters.tet_min_dihedral = 80.0"},
      {[](v1::PipelineParameters* p) { p->set_plc_lattice(0.1); },
       "parameters.plc_lattice = 0.1"},
      {[](v1::PipelineParameters* p) { p->set_config_json("{\"surface\": {\"rr\": 3}}"); },
       "parameters.config_json: unknown key 'surface.rr'"},
      {[](v1::PipelineParameters* p) {
         p->set_config_json("{\"tet\": {\"program\": \"/bin/sh\"}}");
       },
       "a job may not set it"},
      {[](v1::PipelineParameters* p) {
         p->add_labels(255);
         p->add_window(0);
         p->add_window(1);
       },
       "parameters.labels and parameters.window exclude each other"},
      {[](v1::PipelineParameters* p) { p->set_config_json("{not json"); },
       "parameters.config_json"},
  };
  int i = 0;
  for (const Case& c : cases) {
    v1::CreateJobRequest r;
    r.set_request_id(absl::StrCat("bad-", i++));
    r.mutable_input()->set_volume_path(vol);
    c.set(r.mutable_parameters());
    auto job = client_->CreateJob(r);
    EXPECT_EQ(job.status().code(), absl::StatusCode::kInvalidArgument) << c.field;
    EXPECT_THAT(job.status().message(), HasSubstr(c.field));
  }
  // A request without request_id or input is refused too.
  v1::CreateJobRequest r;
  r.mutable_input()->set_volume_path(vol);
  EXPECT_THAT(client_->CreateJob(r).status().message(), HasSubstr("request_id"));
  r.set_request_id("no-input");
  r.clear_input();
  EXPECT_EQ(client_->CreateJob(r).status().code(), absl::StatusCode::kInvalidArgument);
  // A digest the server does not hold.
  v1::CreateJobRequest unknown;
  unknown.set_request_id("unknown-digest");
  unknown.mutable_input()->mutable_volume_digest()->set_hash(std::string(64, 'a'));
  unknown.mutable_input()->mutable_volume_digest()->set_size_bytes(10);
  EXPECT_EQ(client_->CreateJob(unknown).status().code(), absl::StatusCode::kFailedPrecondition);
  // Nothing was queued by any of it.
  auto all = client_->ListJobs(v1::ListJobsRequest());
  ASSERT_TRUE(all.ok());
  EXPECT_EQ(all->jobs_size(), 0);
}

TEST_F(ServiceTest, UnparsableVolumeFailsTheJobWithTheReadersMessage) {
  StartServer();
  const std::string junk = dir_.File("junk.nrrd");
  std::ofstream(junk) << "NRRD0004\ntype: complex\ndimension: 3\nsizes: 4 4 4\nencoding: raw\n\n";
  auto d = client_->Upload(junk);
  ASSERT_TRUE(d.ok());
  auto job = client_->CreateJob(UploadRequest(*d, "junk.nrrd", "junk"));
  ASSERT_TRUE(job.ok()) << job.status();
  const v1::Job end = WaitFinished(job->name());
  EXPECT_EQ(end.state(), v1::FAILED);
  EXPECT_THAT(end.error().message(), HasSubstr("junk.nrrd"));
  EXPECT_THAT(end.error().message(), HasSubstr("complex"));
  EXPECT_EQ(end.error().code(), static_cast<int>(absl::StatusCode::kInvalidArgument));
  EXPECT_EQ(end.artifacts_size(), 0);
  // A raw file whose size does not fit its dims.
  WriteRandomFile(dir_.File("short_16x16x16_u8.raw"), 1000, 3);
  auto d2 = client_->Upload(dir_.File("short_16x16x16_u8.raw"));
  ASSERT_TRUE(d2.ok());
  auto job2 = client_->CreateJob(UploadRequest(*d2, "short_16x16x16_u8.raw", "short"));
  ASSERT_TRUE(job2.ok());
  const v1::Job end2 = WaitFinished(job2->name());
  EXPECT_EQ(end2.state(), v1::FAILED);
  EXPECT_THAT(end2.error().message(), HasSubstr("short_16x16x16_u8.raw"));
  EXPECT_THAT(end2.error().message(), HasSubstr("1000"));
}

TEST_F(ServiceTest, TokenIsRequiredWhenConfigured) {
  options_.auth_token = "s3cret";
  StartServer();
  EXPECT_TRUE(client_->ListJobs(v1::ListJobsRequest()).ok());
  client::ClientOptions co;
  co.address = absl::StrCat("127.0.0.1:", server_->port());
  auto anonymous = client::SheetmeshClient::Connect(co);
  ASSERT_TRUE(anonymous.ok());
  EXPECT_EQ((*anonymous)->ListJobs(v1::ListJobsRequest()).status().code(),
            absl::StatusCode::kUnauthenticated);
  co.auth_token = "wrong";
  auto wrong = client::SheetmeshClient::Connect(co);
  EXPECT_EQ((*wrong)->GetJob("jobs/x").status().code(), absl::StatusCode::kUnauthenticated);
  WriteRandomFile(dir_.File("a.bin"), 10, 1);
  EXPECT_EQ((*wrong)->Upload(dir_.File("a.bin")).status().code(),
            absl::StatusCode::kUnauthenticated);
  // Health answers without the token (probes carry none).
  auto health = (*anonymous)->Health();
  ASSERT_TRUE(health.ok()) << health.status();
  EXPECT_EQ(*health, "SERVING");
}

TEST_F(ServiceTest, FullQueueIsResourceExhaustedNamingTheLimit) {
  options_.workers = 1;
  options_.limits.max_queued_jobs = 1;
  StartServer();
  const std::string slow = WritePhantom(options_.allowed_roots[0], "slow", 256, 14);
  v1::CreateJobRequest r;
  r.mutable_input()->set_volume_path(slow);
  r.mutable_parameters()->set_extract(true);
  r.set_no_cache(true);
  std::vector<std::string> names;
  r.set_request_id("q-0");
  auto a = client_->CreateJob(r);
  ASSERT_TRUE(a.ok());
  names.push_back(a->name());
  WaitRunning(*client_, a->name(), 1);
  r.set_request_id("q-1");
  auto b = client_->CreateJob(r);
  ASSERT_TRUE(b.ok()) << b.status();
  names.push_back(b->name());
  r.set_request_id("q-2");
  auto c = client_->CreateJob(r);
  EXPECT_EQ(c.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(c.status().message(), HasSubstr("max_queued_jobs = 1"));
  // A retry of an accepted request still gets its job.
  r.set_request_id("q-1");
  auto b2 = client_->CreateJob(r);
  ASSERT_TRUE(b2.ok());
  EXPECT_EQ(b2->name(), b->name());
  for (const auto& n : names) ASSERT_TRUE(client_->CancelJob(n).ok());
  for (const auto& n : names) EXPECT_EQ(WaitFinished(n).state(), v1::CANCELLED);
}

// ---------------------------------------------------------------------------------------
// Load

TEST_F(ServiceTest, SixteenClientsFourJobsEach) {
  StartServer();
  std::vector<std::string> volumes;
  for (int i = 0; i < 4; ++i)
    volumes.push_back(WritePhantom(dir_.path(), absl::StrCat("load", i), 40, 100 + i));
  const int64_t rss_before = ProcessRssBytes();
  constexpr int kClients = 16, kJobs = 4;
  std::atomic<int> succeeded{0}, failed{0};
  std::vector<std::thread> threads;
  const std::string address = absl::StrCat("127.0.0.1:", server_->port());
  for (int c = 0; c < kClients; ++c) {
    threads.emplace_back([&, c] {
      client::ClientOptions co;
      co.address = address;
      auto cl = client::SheetmeshClient::Connect(co);
      if (!cl.ok()) {
        failed += kJobs;
        return;
      }
      for (int j = 0; j < kJobs; ++j) {
        const std::string& vol = volumes[(c + j) % volumes.size()];
        auto d = (*cl)->Upload(vol);
        if (!d.ok()) {
          ++failed;
          ADD_FAILURE() << d.status();
          continue;
        }
        v1::CreateJobRequest r;
        r.set_request_id(absl::StrCat("load-", c, "-", j));
        *r.mutable_input()->mutable_volume_digest() = *d;
        r.mutable_input()->set_file_name(std::filesystem::path(vol).filename());
        r.set_no_cache(true);  // every job runs
        auto job = (*cl)->CreateJob(r);
        if (!job.ok()) {
          ++failed;
          ADD_FAILURE() << job.status();
          continue;
        }
        auto end = (*cl)->Watch(job->name(), {});
        if (end.ok() && end->state() == v1::SUCCEEDED) {
          ++succeeded;
        } else {
          ++failed;
          ADD_FAILURE() << (end.ok() ? end->error().message() : end.status().ToString());
        }
      }
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(succeeded.load(), kClients * kJobs);
  EXPECT_EQ(failed.load(), 0);
  v1::ListJobsRequest req;
  req.set_page_size(1000);
  auto all = client_->ListJobs(req);
  ASSERT_TRUE(all.ok());
  EXPECT_EQ(all->jobs_size(), kClients * kJobs);
  for (const auto& j : all->jobs()) EXPECT_EQ(j.state(), v1::SUCCEEDED) << j.name();
  // Memory stays bounded: 64 jobs on 64 KB volumes must not grow the process by more
  // than a few hundred MB (the pipeline's own buffers are freed after each job).
  const int64_t growth = ProcessRssBytes() - rss_before;
  EXPECT_LT(growth, int64_t{400} << 20) << "RSS grew by " << (growth >> 20) << " MiB";
}

}  // namespace
}  // namespace sheetmesh::testing
