// An embedded sheetmesh server on a loopback port with its own data folder, a client for
// it, and phantom volumes to feed it — for tests of the service over real gRPC.
#ifndef SHEETMESH_TESTS_SERVER_SERVICE_FIXTURE_H_
#define SHEETMESH_TESTS_SERVER_SERVICE_FIXTURE_H_

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "client/client.h"
#include "common/file_util.h"
#include "server/server.h"
#include "tests/testing/temp_dir.h"
#include "worker/pipeline/phantom/phantom.h"
#include "worker/pipeline/volume/raw_io.h"

namespace sheetmesh::testing {

// Writes a seeded phantom of n^3 voxels as <dir>/<stem>_<n>x<n>x<n>_u8.raw; returns its path.
inline std::string WritePhantom(const std::string& dir, const std::string& stem, int n,
                                uint64_t seed) {
  PhantomOptions o;
  o.dims = {n, n, n};
  o.seed = seed;
  o.num_sheets = 3;
  o.aperture_voxels = 4;
  auto truth = PlanPhantom(o);
  EXPECT_TRUE(truth.ok()) << truth.status();
  const std::string path = absl::StrCat(dir, "/", stem, "_", n, "x", n, "x", n, "_u8.raw");
  VolumeInfo info;
  info.dims = o.dims;
  info.dtype = DType::kUInt8;
  auto sink = CreateRawWriter(path, info);
  EXPECT_TRUE(sink.ok()) << sink.status();
  absl::Status st = GeneratePhantom(&*truth, **sink);
  EXPECT_TRUE(st.ok()) << st;
  return path;
}

class ServiceTest : public ::testing::Test {
 protected:
  // Starts the server; tests that need other options change options_ and call it again.
  void StartServer() {
    server_.reset();
    auto s = server::Server::Start(options_);
    ASSERT_TRUE(s.ok()) << s.status();
    server_ = std::move(*s);
    client::ClientOptions co;
    co.address = absl::StrCat("127.0.0.1:", server_->port());
    co.auth_token = options_.auth_token;
    auto c = client::SheetmeshClient::Connect(co);
    ASSERT_TRUE(c.ok()) << c.status();
    client_ = std::move(*c);
  }

  void SetUp() override {
    options_.address = "127.0.0.1:0";
    options_.data_dir = dir_.File("data");
    options_.workers = 2;
    options_.heartbeat = absl::Milliseconds(500);
    // Jobs run in children of the real server program (this test binary cannot be one).
    options_.job_program = SHEETMESH_SERVER_BIN;
    std::filesystem::create_directories(dir_.File("root"));
    options_.allowed_roots = {dir_.File("root")};
  }

  void TearDown() override {
    if (server_) server_->Shutdown(absl::Seconds(5));
  }

  // A CreateJobRequest for an uploaded file.
  v1::CreateJobRequest UploadRequest(const v1::Digest& digest, const std::string& file_name,
                                     const std::string& request_id) {
    v1::CreateJobRequest r;
    r.set_request_id(request_id);
    *r.mutable_input()->mutable_volume_digest() = digest;
    r.mutable_input()->set_file_name(file_name);
    return r;
  }

  v1::Job WaitFinished(const std::string& name) {
    auto job = client_->Watch(name, {});
    EXPECT_TRUE(job.ok()) << job.status();
    return job.ok() ? *job : v1::Job();
  }

  TempDir dir_;
  server::ServerOptions options_;
  std::unique_ptr<server::Server> server_;
  std::unique_ptr<client::SheetmeshClient> client_;
};

inline std::string WriteRandomFile(const std::string& path, int64_t size, uint32_t seed) {
  std::mt19937 gen(seed);
  std::string bytes(size, '\0');
  for (auto& c : bytes) c = static_cast<char>(gen());
  std::ofstream(path, std::ios::binary).write(bytes.data(), bytes.size());
  return bytes;
}

inline std::string Slurp(const std::string& path) {
  auto s = ReadFileToString(path);
  EXPECT_TRUE(s.ok()) << s.status();
  return s.ok() ? *s : "";
}

inline std::vector<v1::Digest> Missing(client::SheetmeshClient& c, const v1::Digest& d) {
  v1::FindMissingBlobsRequest req;
  *req.add_digests() = d;
  v1::FindMissingBlobsResponse resp;
  grpc::Status st = c.blobs()->FindMissingBlobs(c.Context().get(), req, &resp);
  EXPECT_TRUE(st.ok()) << st.error_message();
  return {resp.missing().begin(), resp.missing().end()};
}

inline int64_t ProcessRssBytes() {
  std::ifstream f("/proc/self/statm");
  int64_t pages = 0, resident = 0;
  f >> pages >> resident;
  return resident * ::sysconf(_SC_PAGESIZE);
}

// Polls until the job is RUNNING at stage `stage` or later (or finished); returns the job.
inline v1::Job WaitRunning(client::SheetmeshClient& c, const std::string& name, int min_stage) {
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

}  // namespace sheetmesh::testing

#endif  // SHEETMESH_TESTS_SERVER_SERVICE_FIXTURE_H_
