// The audit's second round at the blob and worker services, over real gRPC: unfinished
// uploads have a quota per tenant and stop above the free-disk floor (and the job store is
// never starved by them), ranged reads whose limit overflows read to the end, and a worker
// may finish a job only with artifacts it uploaded for that job, under plain file names.
#include <gmock/gmock.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <sys/statvfs.h>

#include <climits>
#include <fstream>

#include "absl/strings/str_cat.h"
#include "common/sha256.h"
#include "sheetmesh/v1/workers.grpc.pb.h"
#include "tests/server/service_fixture.h"

namespace sheetmesh::testing {
namespace {

using ::testing::HasSubstr;

constexpr char kAlice[] = "token-of-alice-0123456789";
constexpr char kBob[] = "token-of-bob-0123456789";
constexpr char kWorkerToken[] = "token-of-the-workers-0123456789";

class UploadHardeningTest : public ServiceTest {
 protected:
  void SetUp() override {
    ServiceTest::SetUp();
    std::ofstream(dir_.File("tokens")) << kAlice << " alice\n" << kBob << " bob\n";
    std::ofstream(dir_.File("worker-token")) << kWorkerToken << "\n";
    options_.auth_token_file = dir_.File("tokens");
    options_.worker_token_file = dir_.File("worker-token");
  }

  std::unique_ptr<client::SheetmeshClient> As(const std::string& token,
                                              const std::string& job = "",
                                              const std::string& worker = "") {
    client::ClientOptions co;
    co.address = absl::StrCat("127.0.0.1:", server_->port());
    co.auth_token = token;
    co.artifact_job = job;
    co.artifact_worker = worker;
    co.upload_retries = 0;
    auto c = client::SheetmeshClient::Connect(co);
    EXPECT_TRUE(c.ok()) << c.status();
    return std::move(*c);
  }

  // Sends `bytes` zero bytes of an upload declaring `declared` bytes, in 1 MiB pieces, and
  // leaves it unfinished. Returns the stream's status.
  static grpc::Status SendUnfinished(client::SheetmeshClient& c, const std::string& id,
                                     int64_t bytes, int64_t declared) {
    v1::Digest d;
    d.set_hash(Sha256Hex(id));  // never checked: the upload does not finish
    d.set_size_bytes(declared);
    auto ctx = c.Context();
    v1::WriteResponse resp;
    auto writer = c.blobs()->Write(ctx.get(), &resp);
    v1::WriteRequest req;
    req.set_resource_name(
        absl::StrCat("uploads/", id, "/blobs/", d.hash(), "/", d.size_bytes()));
    const std::string piece(1 << 20, '\0');
    for (int64_t at = 0; at < bytes; at += piece.size()) {
      req.set_write_offset(at);
      req.set_data(piece.substr(0, std::min<int64_t>(piece.size(), bytes - at)));
      if (!writer->Write(req)) break;
      req.clear_resource_name();
    }
    writer->WritesDone();
    return writer->Finish();
  }

  std::string QueuedJob(client::SheetmeshClient& c, const std::string& id, int n = 24) {
    const std::string path = WritePhantom(dir_.path(), id, n, 5);
    auto digest = c.Upload(path);
    EXPECT_TRUE(digest.ok()) << digest.status();
    auto job =
        c.CreateJob(UploadRequest(*digest, std::filesystem::path(path).filename().string(), id));
    EXPECT_TRUE(job.ok()) << job.status();
    return job.ok() ? job->name() : "";
  }
};

TEST_F(UploadHardeningTest, UnfinishedUploadsHaveAQuotaPerTenantAndStarveNoJob) {
  options_.local_workers = false;
  options_.limits.max_unfinished_upload_bytes_per_tenant = int64_t{64} << 20;
  StartServer();
  auto alice = As(kAlice);
  auto bob = As(kBob);
  // The audit's 30 MiB streams that never finish: two fit alice's 64 MiB, the third not.
  EXPECT_TRUE(SendUnfinished(*alice, "a1", 30 << 20, 40 << 20).ok());
  EXPECT_TRUE(SendUnfinished(*alice, "a2", 30 << 20, 40 << 20).ok());
  const grpc::Status third = SendUnfinished(*alice, "a3", 30 << 20, 40 << 20);
  EXPECT_EQ(third.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(third.error_message(),
              ::testing::AllOf(HasSubstr("alice"), HasSubstr("--max_unfinished_upload_mb")));
  // Bob's uploads and jobs go on; so do alice's jobs.
  EXPECT_TRUE(SendUnfinished(*bob, "b1", 30 << 20, 40 << 20).ok());
  EXPECT_FALSE(QueuedJob(*bob, "bobs-job").empty());
  auto jobs = alice->ListJobs(v1::ListJobsRequest());
  EXPECT_TRUE(jobs.ok()) << jobs.status();
}

TEST_F(UploadHardeningTest, UploadsStopAboveTheFreeDiskFloorAndJobsStillStart) {
  std::filesystem::create_directories(options_.data_dir);
  struct statvfs fs;
  ASSERT_EQ(::statvfs(options_.data_dir.c_str(), &fs), 0);
  const int64_t free_now = static_cast<int64_t>(fs.f_bavail) * fs.f_frsize;
  // A floor 48 MiB under what is free now: an upload of 1 GiB stops within 48 MiB (other
  // processes writing meanwhile only bring the refusal earlier).
  options_.min_free_disk_bytes = free_now - (int64_t{48} << 20);
  options_.local_workers = false;
  StartServer();
  auto alice = As(kAlice);
  const grpc::Status big = SendUnfinished(*alice, "big", int64_t{1} << 30, int64_t{1} << 30);
  EXPECT_EQ(big.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(big.error_message(), HasSubstr("--min_free_disk_mb"));
  // The job store has its room: a job from a stored blob is still accepted.
  auto bob = As(kBob);
  const std::string path = WritePhantom(dir_.path(), "tiny", 16, 5);
  std::filesystem::copy_file(path, dir_.File("root/tiny_16x16x16_u8.raw"));
  v1::CreateJobRequest r;
  r.set_request_id("by-reference");
  r.mutable_input()->set_volume_path(dir_.File("root/tiny_16x16x16_u8.raw"));
  auto job = bob->CreateJob(r);
  EXPECT_TRUE(job.ok()) << job.status();
}

TEST_F(UploadHardeningTest, AReadLimitThatOverflowsReadsToTheEnd) {
  StartServer();
  auto alice = As(kAlice);
  const std::string bytes = WriteRandomFile(dir_.File("blob"), 3 << 20, 9);
  auto digest = alice->Upload(dir_.File("blob"));
  ASSERT_TRUE(digest.ok()) << digest.status();
  v1::ReadRequest req;
  *req.mutable_digest() = *digest;
  req.set_read_offset(1);
  req.set_read_limit(INT64_MAX);
  auto ctx = alice->Context();
  auto reader = alice->blobs()->Read(ctx.get(), req);
  std::string got;
  v1::ReadResponse resp;
  while (reader->Read(&resp)) got += resp.data();
  ASSERT_TRUE(reader->Finish().ok());
  EXPECT_EQ(got.size(), bytes.size() - 1);
  EXPECT_EQ(got, bytes.substr(1));
}

class ArtifactProvenanceTest : public UploadHardeningTest {
 protected:
  void SetUp() override {
    UploadHardeningTest::SetUp();
    options_.local_workers = false;  // the test is the worker
  }

  void Connect() {
    channel_ = grpc::CreateChannel(absl::StrCat("127.0.0.1:", server_->port()),
                                   grpc::InsecureChannelCredentials());
    workers_ = v1::WorkerService::NewStub(channel_);
  }

  std::unique_ptr<grpc::ClientContext> WorkerContext() {
    auto ctx = std::make_unique<grpc::ClientContext>();
    ctx->AddMetadata("authorization", absl::StrCat("Bearer ", kWorkerToken));
    return ctx;
  }

  std::string Lease(const std::string& worker) {
    v1::LeaseJobRequest req;
    req.set_worker(worker);
    v1::LeaseJobResponse resp;
    const grpc::Status st = workers_->LeaseJob(WorkerContext().get(), req, &resp);
    EXPECT_TRUE(st.ok()) << st.error_message();
    return resp.job().name();
  }

  grpc::Status Finish(const std::string& job, const std::string& worker,
                      const std::string& name, const v1::Digest& digest, v1::Job* done) {
    v1::FinishJobRequest req;
    req.set_name(job);
    req.set_worker(worker);
    req.set_state(v1::SUCCEEDED);
    v1::Artifact* a = req.add_artifacts();
    a->set_name(name);
    *a->mutable_digest() = digest;
    return workers_->FinishJob(WorkerContext().get(), req, done);
  }

  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::WorkerService::Stub> workers_;
};

TEST_F(ArtifactProvenanceTest, AJobTakesOnlyArtifactsItsWorkerUploadedForItUnderPlainNames) {
  StartServer();
  Connect();
  auto alice = As(kAlice);
  auto bob = As(kBob);
  const std::string job1 = QueuedJob(*alice, "first");
  const std::string job2 = QueuedJob(*bob, "second");
  // Bob's volume, stored: a worker may not hand it to alice's job by naming its digest.
  const std::string bobs_volume = WritePhantom(dir_.path(), "second", 24, 5);
  auto bobs = server::DigestOfFile(bobs_volume);
  ASSERT_TRUE(bobs.ok());
  ASSERT_EQ(Lease("w1"), job1);
  ASSERT_EQ(Lease("w2"), job2);
  // The worker uploads an output for its job; the same bytes as bob's volume must still
  // travel (knowing a digest is not having the content).
  std::filesystem::copy_file(bobs_volume, dir_.File("output.raw"));
  WriteRandomFile(dir_.File("report.json"), 1000, 3);
  auto as_w1 = As(kWorkerToken, job1, "w1");
  auto mine = as_w1->Upload(dir_.File("report.json"));
  ASSERT_TRUE(mine.ok()) << mine.status();
  auto copy = as_w1->Upload(dir_.File("output.raw"));
  ASSERT_TRUE(copy.ok()) << copy.status();
  // Uploading for a job it does not hold is refused.
  auto as_w1_for_job2 = As(kWorkerToken, job2, "w1");
  EXPECT_EQ(as_w1_for_job2->Upload(dir_.File("report.json")).status().code(),
            absl::StatusCode::kPermissionDenied);
  v1::Job done;
  // A name that leaves the folder, or hides, is refused whatever the blob.
  for (const std::string bad : {"../../etc/passwd", "a/b.json", ".hidden", "", "x\ny"}) {
    const grpc::Status st = Finish(job1, "w1", bad, *mine, &done);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << bad;
  }
  // Bob's stored volume was not uploaded for job2 by w2.
  const grpc::Status foreign = Finish(job2, "w2", "volume.raw", *bobs, &done);
  EXPECT_EQ(foreign.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_THAT(foreign.error_message(), HasSubstr("not uploaded for " + job2));
  // job1's output is not job2's.
  EXPECT_EQ(Finish(job2, "w2", "report.json", *mine, &done).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  // Its own upload finishes it, and alice reads it back.
  const grpc::Status ok = Finish(job1, "w1", "report.json", *mine, &done);
  ASSERT_TRUE(ok.ok()) << ok.error_message();
  EXPECT_EQ(done.state(), v1::SUCCEEDED);
  EXPECT_TRUE(alice->Download(*mine, dir_.File("back.json")).ok());
  EXPECT_EQ(Slurp(dir_.File("back.json")), Slurp(dir_.File("report.json")));
}

}  // namespace
}  // namespace sheetmesh::testing
