#include "worker/runtime/worker_pool.h"

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <optional>

#include "tests/server/service_fixture.h"
#include "tests/testing/temp_dir.h"

namespace sheetmesh::runtime {
namespace {

// A host (a fake, the layer below the pool) whose job is cancelled and says so only when
// its lease is renewed: the progress reports never say stop.
class CancelledAtRenewalHost : public JobHost {
 public:
  explicit CancelledAtRenewalHost(std::string volume) : volume_(std::move(volume)) {}

  absl::StatusOr<std::optional<v1::Job>> Lease(const std::string&, absl::Duration wait) override {
    std::unique_lock<std::mutex> lock(mu_);
    if (!leased_) {
      leased_ = true;
      v1::Job job;
      job.set_name("jobs/1");
      job.mutable_input()->set_volume_path(volume_);
      job.mutable_parameters()->set_r(5);
      job.mutable_parameters()->set_volume_mesh(true);  // long enough for renewals
      return std::optional<v1::Job>(job);
    }
    cv_.wait_for(lock, absl::ToChronoMilliseconds(wait));
    return std::optional<v1::Job>();
  }
  absl::Status Renew(const std::string& job, const std::string&) override {
    std::lock_guard<std::mutex> lock(mu_);
    ++renewals_;
    return absl::CancelledError(job + " was cancelled");
  }
  bool ReportProgress(const std::string&, const std::string&, const ProgressUpdate&) override {
    return true;
  }
  absl::StatusOr<LocalVolume> ResolveInput(const v1::Job& job,
                                           const std::vector<ByteRange>* /*only*/) override {
    return LocalVolume{job.input().volume_path(), "rock", false, {}};
  }
  absl::StatusOr<v1::Artifact> PutArtifact(const std::string&, const std::string&,
                                           const std::string&, const std::string&) override {
    return v1::Artifact();
  }
  absl::Status Finish(const std::string&, const std::string&, const absl::Status& result,
                      const std::vector<v1::Artifact>&) override {
    std::lock_guard<std::mutex> lock(mu_);
    finished_ = result;
    cv_.notify_all();
    return absl::OkStatus();
  }
  absl::Status Release(const std::string&, const std::string&) override {
    std::lock_guard<std::mutex> lock(mu_);
    released_ = true;
    cv_.notify_all();
    return absl::OkStatus();
  }
  absl::Status Split(const std::string&, const std::string&, const v1::Artifact&, int) override {
    return absl::UnimplementedError("no bricks here");
  }
  absl::Status FetchBlob(const v1::Digest&, const std::string&) override {
    return absl::UnimplementedError("no blobs here");
  }

  // Waits until the job was finished or released; false if neither came (a job left to
  // its lease: the bound only keeps a failure from hanging the suite).
  bool WaitEnded() {
    std::unique_lock<std::mutex> lock(mu_);
    return cv_.wait_for(lock, std::chrono::minutes(2),
                        [&] { return finished_.has_value() || released_; });
  }

  std::mutex mu_;
  std::condition_variable cv_;
  std::string volume_;
  bool leased_ = false, released_ = false;
  int renewals_ = 0;
  std::optional<absl::Status> finished_;
};

TEST(WorkerPoolTest, ACancelHeardAtARenewalEndsTheJobCancelled) {
  // Once a cancel heard first at a renewal counted as a lost lease: the worker reported
  // nothing, and the job stayed RUNNING until its lease ran out.
  sheetmesh::testing::TempDir tmp;
  CancelledAtRenewalHost host(sheetmesh::testing::WritePhantom(tmp.path(), "rock", 64, 3));
  WorkerPoolOptions o;
  o.workers = 1;
  o.run.isolate = false;
  o.run.scratch_dir = tmp.path();
  o.renew_interval = absl::Milliseconds(1);
  o.lease_poll = absl::Milliseconds(20);
  WorkerPool pool(&host, o);
  pool.Start();
  const bool ended = host.WaitEnded();
  pool.Stop();
  EXPECT_TRUE(ended) << "the worker reported nothing: the job would wait out its lease";
  std::lock_guard<std::mutex> lock(host.mu_);
  EXPECT_GT(host.renewals_, 0);
  ASSERT_TRUE(host.finished_.has_value()) << "the job was not ended (released instead)";
  EXPECT_EQ(host.finished_->code(), absl::StatusCode::kCancelled) << *host.finished_;
}

}  // namespace
}  // namespace sheetmesh::runtime
