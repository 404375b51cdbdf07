// Durability of the real server process: SIGKILL it mid-job and mid-upload, start it
// again on the same data folder, and nothing accepted is lost.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <random>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "client/client.h"
#include "common/file_util.h"
#include "server/blob_store.h"
#include "tests/server/service_fixture.h"

namespace sheetmesh::testing {
namespace {

// The sheetmesh-server binary as a child process.
class ServerProcess {
 public:
  ServerProcess(std::string data_dir, std::string root, std::vector<std::string> extra = {})
      : data_dir_(std::move(data_dir)), root_(std::move(root)), extra_(std::move(extra)) {}
  ~ServerProcess() { Kill(SIGKILL); }

  void Start() {
    const std::string port_file = data_dir_ + ".port";
    ::unlink(port_file.c_str());
    std::vector<std::string> args = {SHEETMESH_SERVER_BIN,      "--address=127.0.0.1:0",
                                     "--data_dir=" + data_dir_, "--port_file=" + port_file,
                                     "--allowed_root=" + root_, "--workers=1",
                                     "--lease_seconds=3"};
    args.insert(args.end(), extra_.begin(), extra_.end());
    pid_ = ::fork();
    ASSERT_GE(pid_, 0);
    if (pid_ == 0) {
      std::vector<char*> argv;
      for (auto& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    const absl::Time deadline = absl::Now() + absl::Seconds(30);
    for (;;) {
      auto text = ReadFileToString(port_file);
      if (text.ok() && !text->empty() && text->back() == '\n') {
        port_ = std::stoi(*text);
        break;
      }
      ASSERT_LT(absl::Now(), deadline) << "the server did not start";
      absl::SleepFor(absl::Milliseconds(20));
    }
    client::ClientOptions co;
    co.address = absl::StrCat("127.0.0.1:", port_);
    auto c = client::SheetmeshClient::Connect(co);
    ASSERT_TRUE(c.ok());
    client_ = std::move(*c);
  }

  // Sends `signal` and reaps the process; returns its wait status.
  int Kill(int signal) {
    if (pid_ <= 0) return 0;
    ::kill(pid_, signal);
    int status = 0;
    ::waitpid(pid_, &status, 0);
    pid_ = -1;
    return status;
  }

  client::SheetmeshClient& client() { return *client_; }

 private:
  std::string data_dir_, root_;
  std::vector<std::string> extra_;
  pid_t pid_ = -1;
  int port_ = 0;
  std::unique_ptr<client::SheetmeshClient> client_;
};

TEST(DurabilityTest, SigkillMidJobThenRestartFinishesEveryAcceptedJob) {
  TempDir dir;
  std::filesystem::create_directories(dir.File("root"));
  const std::string slow = WritePhantom(dir.File("root"), "slow", 256, 21);
  const std::string small = WritePhantom(dir.File("root"), "small", 40, 22);
  ServerProcess server(dir.File("data"), dir.File("root"));
  server.Start();
  v1::CreateJobRequest a;
  a.set_request_id("running-when-killed");
  a.mutable_input()->set_volume_path(slow);
  a.mutable_parameters()->set_extract(true);
  auto ja = server.client().CreateJob(a);
  ASSERT_TRUE(ja.ok()) << ja.status();
  v1::CreateJobRequest b;
  b.set_request_id("queued-when-killed");
  b.mutable_input()->set_volume_path(small);
  auto jb = server.client().CreateJob(b);
  ASSERT_TRUE(jb.ok()) << jb.status();
  // Kill it once the first job is well into its run.
  const absl::Time deadline = absl::Now() + absl::Seconds(60);
  for (;;) {
    auto j = server.client().GetJob(ja->name());
    ASSERT_TRUE(j.ok());
    if (j->state() == v1::RUNNING && j->progress().stage_index() >= 2) break;
    ASSERT_NE(j->state(), v1::SUCCEEDED) << "the job ended before the kill";
    ASSERT_LT(absl::Now(), deadline);
    absl::SleepFor(absl::Milliseconds(20));
  }
  const int status = server.Kill(SIGKILL);
  ASSERT_TRUE(WIFSIGNALED(status));

  server.Start();
  // Both jobs are there and finish; the killed run is an attempt lost to the restart.
  auto ea = server.client().Watch(ja->name(), {});
  ASSERT_TRUE(ea.ok()) << ea.status();
  EXPECT_EQ(ea->state(), v1::SUCCEEDED) << ea->error().message();
  EXPECT_EQ(ea->attempts(), 2);
  EXPECT_EQ(ea->lost_to_restarts(), 1);
  auto eb = server.client().Watch(jb->name(), {});
  ASSERT_TRUE(eb.ok()) << eb.status();
  EXPECT_EQ(eb->state(), v1::SUCCEEDED) << eb->error().message();
  // The same request after the restart is still the same job.
  auto again = server.client().CreateJob(a);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(again->name(), ja->name());
  // Every artifact reads back with its digest (Download checks the SHA-256).
  ASSERT_GT(ea->artifacts_size(), 3);
  for (const auto& art : ea->artifacts()) {
    const std::string out = dir.File("out_" + art.name());
    ASSERT_TRUE(server.client().Download(art.digest(), out).ok()) << art.name();
    auto d = server::DigestOfFile(out);
    ASSERT_TRUE(d.ok());
    EXPECT_EQ(d->hash(), art.digest().hash()) << art.name();
    EXPECT_EQ(d->size_bytes(), art.digest().size_bytes()) << art.name();
  }
  // No scratch left behind by the killed run once the job is done.
  EXPECT_EQ(server.Kill(SIGTERM), 0);
}

// Waits until `job` runs its stage `stage` or later.
void AwaitStage(client::SheetmeshClient& c, const std::string& job, int stage) {
  const absl::Time deadline = absl::Now() + absl::Seconds(60);
  for (;;) {
    auto j = c.GetJob(job);
    ASSERT_TRUE(j.ok()) << j.status();
    if (j->state() == v1::RUNNING && j->progress().stage_index() >= stage) return;
    ASSERT_NE(j->state(), v1::SUCCEEDED) << "the job ended before the kill";
    ASSERT_LT(absl::Now(), deadline);
    absl::SleepFor(absl::Milliseconds(20));
  }
}

TEST(DurabilityTest, AServerKilledMoreOftenThanMaxAttemptsFailsNoneOfItsJobs) {
  TempDir dir;
  std::filesystem::create_directories(dir.File("root"));
  const std::string slow = WritePhantom(dir.File("root"), "slow", 200, 23);
  // One attempt allowed: every kill of the server would fail the job if it counted.
  ServerProcess server(dir.File("data"), dir.File("root"), {"--max_attempts=1"});
  server.Start();
  v1::CreateJobRequest a;
  a.set_request_id("killed-twice");
  a.mutable_input()->set_volume_path(slow);
  a.mutable_parameters()->set_extract(true);
  auto job = server.client().CreateJob(a);
  ASSERT_TRUE(job.ok()) << job.status();
  for (int kill = 0; kill < 2; ++kill) {
    AwaitStage(server.client(), job->name(), 1);
    ASSERT_TRUE(WIFSIGNALED(server.Kill(SIGKILL)));
    server.Start();
  }
  auto done = server.client().Watch(job->name(), {});
  ASSERT_TRUE(done.ok()) << done.status();
  EXPECT_EQ(done->state(), v1::SUCCEEDED) << done->error().message();
  EXPECT_EQ(done->attempts(), 3);
  EXPECT_EQ(done->lost_to_restarts(), 2);
  EXPECT_EQ(server.Kill(SIGTERM), 0);
}

TEST(DurabilityTest, UploadInterruptedByAKillResumesAfterRestart) {
  TempDir dir;
  std::filesystem::create_directories(dir.File("root"));
  const std::string path = dir.File("volume.bin");
  std::string bytes(13 * (1 << 20) + 3, '\0');
  std::mt19937 gen(5);
  for (auto& c : bytes) c = static_cast<char>(gen());
  std::ofstream(path, std::ios::binary).write(bytes.data(), bytes.size());
  auto digest = server::DigestOfFile(path);
  ASSERT_TRUE(digest.ok());
  const std::string resource = absl::StrCat("uploads/u", digest->hash().substr(0, 32), "/blobs/",
                                            digest->hash(), "/", digest->size_bytes());
  ServerProcess server(dir.File("data"), dir.File("root"));
  server.Start();
  {
    auto ctx = server.client().Context();
    v1::WriteResponse resp;
    auto writer = server.client().blobs()->Write(ctx.get(), &resp);
    // Ten pieces: the server writes its 8 MiB buffer straight to the disk as it fills;
    // the two pieces still in the buffer die with the process.
    for (int i = 0; i < 10; ++i) {
      v1::WriteRequest req;
      if (i == 0) req.set_resource_name(resource);
      req.set_write_offset(int64_t{i} << 20);
      req.set_data(bytes.substr(static_cast<size_t>(i) << 20, size_t{1} << 20));
      ASSERT_TRUE(writer->Write(req));
    }
    // Killed once the server has written its first 8 MiB out (what it reports durable).
    v1::QueryWriteStatusRequest q;
    q.set_resource_name(resource);
    v1::QueryWriteStatusResponse qs;
    const absl::Time deadline = absl::Now() + absl::Seconds(30);
    while (absl::Now() < deadline) {
      ASSERT_TRUE(
          server.client().blobs()->QueryWriteStatus(server.client().Context().get(), q, &qs).ok());
      if (qs.committed_size() >= 8 << 20) break;
      absl::SleepFor(absl::Milliseconds(20));
    }
    server.Kill(SIGKILL);
    EXPECT_FALSE(writer->Finish().ok());
  }
  server.Start();
  v1::QueryWriteStatusRequest q;
  q.set_resource_name(resource);
  v1::QueryWriteStatusResponse qs;
  ASSERT_TRUE(
      server.client().blobs()->QueryWriteStatus(server.client().Context().get(), q, &qs).ok());
  EXPECT_EQ(qs.committed_size(), 8 << 20);
  int64_t first = -1;
  auto up = server.client().Upload(path, [&](int64_t sent, int64_t) {
    if (first < 0) first = sent;
  });
  ASSERT_TRUE(up.ok()) << up.status();
  EXPECT_EQ(first, 9 << 20);  // resumed after the eight pieces on the disk
  ASSERT_TRUE(server.client().Download(*digest, dir.File("back.bin")).ok());
  auto back = ReadFileToString(dir.File("back.bin"));
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(*back, bytes);
}

}  // namespace
}  // namespace sheetmesh::testing
