// The service over real gRPC on loopback: references and their roots, bad parameters and
// volumes, the token, the queue's limit and load, against an embedded server with its own
// data folder.
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
#include "common/file_util.h"
#include "nlohmann/json.hpp"
#include "server/blob_store.h"
#include "tests/server/service_fixture.h"

namespace sheetmesh::testing {
namespace {

using ::testing::HasSubstr;

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
  r.mutable_parameters()->set_extract(false);  // 32³ holds no piece of extraction's M
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
      {[](v1::PipelineParameters* p) { p->set_plc_lattice(0.1); }, "parameters.plc_lattice = 0.1"},
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
