// The server's resources and boundaries over real gRPC: uploads hold descriptors only while
// they stream, stall into a timeout and expire; upload and watch streams are limited per
// client and in all (a watch costs no thread); tenants see only their own jobs, uploads and
// artifacts; reflection needs a token; retention collects what no job names; health says
// NOT_SERVING when uploads could not be taken.
#include <dirent.h>
#include <gmock/gmock.h>
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <atomic>
#include <condition_variable>
#include <filesystem>
#include <fstream>
#include <mutex>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/sha256.h"
#include "server/blob_store.h"
#include "tests/server/service_fixture.h"

namespace sheetmesh::testing {
namespace {

using ::testing::HasSubstr;

int OpenDescriptors() {
  int n = 0;
  if (DIR* d = ::opendir("/proc/self/fd")) {
    while (::readdir(d) != nullptr) ++n;
    ::closedir(d);
  }
  return n - 3;
}

int Threads() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind("Threads:", 0) == 0) return std::stoi(line.substr(8));
  }
  return -1;
}

std::string ResourceOf(const std::string& id, const v1::Digest& d) {
  return absl::StrCat("uploads/", id, "/blobs/", d.hash(), "/", d.size_bytes());
}

v1::Digest DigestOfBytes(const std::string& bytes) {
  v1::Digest d;
  d.set_hash(Sha256Hex(bytes));
  d.set_size_bytes(bytes.size());
  return d;
}

// Starts an upload, sends `piece` bytes of `bytes`, and abandons the stream (half-close,
// no finish). Returns the stream's status.
grpc::Status AbandonUpload(client::SheetmeshClient& c, const std::string& resource,
                           const std::string& bytes, size_t piece) {
  auto ctx = c.Context();
  v1::WriteResponse resp;
  auto writer = c.blobs()->Write(ctx.get(), &resp);
  v1::WriteRequest req;
  req.set_resource_name(resource);
  req.set_data(bytes.substr(0, piece));
  writer->Write(req);
  writer->WritesDone();
  return writer->Finish();
}

TEST_F(ServiceTest, AbandonedAndRefusedUploadsHoldNoDescriptors) {
  struct rlimit rl = {1024, 1024};
  ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &rl), 0);
  options_.limits.max_blob_bytes = 1 << 20;
  StartServer();
  ASSERT_EQ(*client_->Health(), "SERVING");
  const int before = OpenDescriptors();
  for (int i = 0; i < 600; ++i) {
    const std::string bytes = absl::StrCat("abandoned upload number ", i, std::string(5000, 'x'));
    grpc::Status st =
        AbandonUpload(*client_, ResourceOf(absl::StrCat("a", i), DigestOfBytes(bytes)), bytes, 100);
    ASSERT_TRUE(st.ok()) << i << ": " << st.error_message();
  }
  for (int i = 0; i < 50; ++i) {  // refused for size, before anything is written
    const std::string big(2 << 20, static_cast<char>(i));
    grpc::Status st =
        AbandonUpload(*client_, ResourceOf(absl::StrCat("big", i), DigestOfBytes(big)), big, 10);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_THAT(st.error_message(), HasSubstr("max_blob_bytes"));
  }
  EXPECT_LT(OpenDescriptors(), before + 16) << "descriptors of ended uploads are closed";
  int parts = 0;
  for (const auto& e :
       std::filesystem::recursive_directory_iterator(options_.data_dir + "/blobs")) {
    parts += e.path().extension() == ".part";
  }
  EXPECT_EQ(parts, 600) << "abandoned uploads stay for resumption; refused ones leave nothing";
  // A good upload after them all, and one of the abandoned ones resumed.
  const std::string good = WritePhantom(dir_.path(), "after", 32, 4);
  EXPECT_TRUE(client_->Upload(good).ok());
  EXPECT_EQ(*client_->Health(), "SERVING");
}

TEST_F(ServiceTest, AStalledUploadIsClosedAndResumes) {
  options_.limits.upload_idle_timeout = absl::Milliseconds(400);
  StartServer();
  const std::string bytes(300000, 'q');
  const v1::Digest d = DigestOfBytes(bytes);
  const std::string resource = ResourceOf("stall", d);
  const int before = OpenDescriptors();
  auto ctx = client_->Context();
  v1::WriteResponse resp;
  auto writer = client_->blobs()->Write(ctx.get(), &resp);
  v1::WriteRequest req;
  req.set_resource_name(resource);
  req.set_data(bytes.substr(0, 100000));
  ASSERT_TRUE(writer->Write(req));
  absl::SleepFor(absl::Seconds(2));  // the client stalls
  EXPECT_EQ(writer->Finish().error_code(), grpc::StatusCode::CANCELLED);
  EXPECT_LE(OpenDescriptors(), before + 2);
  v1::QueryWriteStatusRequest q;
  q.set_resource_name(resource);
  v1::QueryWriteStatusResponse qs;
  ASSERT_TRUE(client_->blobs()->QueryWriteStatus(client_->Context().get(), q, &qs).ok());
  EXPECT_EQ(qs.committed_size(), 100000);
  // Resumed where it stopped.
  auto ctx2 = client_->Context();
  auto w2 = client_->blobs()->Write(ctx2.get(), &resp);
  req.set_write_offset(100000);
  req.set_data(bytes.substr(100000));
  req.set_finish_write(true);
  ASSERT_TRUE(w2->Write(req));
  w2->WritesDone();
  ASSERT_TRUE(w2->Finish().ok());
  EXPECT_TRUE(Missing(*client_, d).empty());
}

TEST_F(ServiceTest, UploadStreamsAreLimitedPerClientNamingTheLimit) {
  options_.limits.max_upload_streams_per_client = 3;
  StartServer();
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<std::unique_ptr<grpc::ClientWriter<v1::WriteRequest>>> writers;
  v1::WriteResponse resp;
  for (int i = 0; i < 3; ++i) {
    const std::string bytes = absl::StrCat("open stream ", i, std::string(1000, 'o'));
    contexts.push_back(client_->Context());
    writers.push_back(client_->blobs()->Write(contexts.back().get(), &resp));
    v1::WriteRequest req;
    req.set_resource_name(ResourceOf(absl::StrCat("o", i), DigestOfBytes(bytes)));
    req.set_data(bytes.substr(0, 10));
    ASSERT_TRUE(writers.back()->Write(req));
  }
  // Once the three are open on the server, a fourth is refused (until then one may pass: it
  // is abandoned, and tried again).
  const std::string extra = "one too many";
  grpc::Status st;
  const absl::Time deadline = absl::Now() + absl::Seconds(30);
  do {
    st = AbandonUpload(*client_, ResourceOf("x", DigestOfBytes(extra)), extra, 3);
  } while (st.error_code() != grpc::StatusCode::RESOURCE_EXHAUSTED && absl::Now() < deadline);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(st.error_message(), HasSubstr("--max_upload_streams_per_client"));
  writers[0]->WritesDone();
  EXPECT_TRUE(writers[0]->Finish().ok());
  EXPECT_TRUE(AbandonUpload(*client_, ResourceOf("y", DigestOfBytes(extra)), extra, 3).ok())
      << "a place freed by a stream that ended";
  for (size_t i = 1; i < writers.size(); ++i) {
    writers[i]->WritesDone();
    writers[i]->Finish();
  }
}

// A watch from the client side: counts its first message and its end.
class WatchReader : public grpc::ClientReadReactor<v1::WatchJobResponse> {
 public:
  WatchReader(v1::JobService::Stub* stub, const std::string& name, const std::string& token,
              std::atomic<int>* opened, std::atomic<int>* refused, std::atomic<int>* ended)
      : opened_(opened), refused_(refused), ended_(ended) {
    if (!token.empty()) context_.AddMetadata("authorization", "Bearer " + token);
    request_.set_name(name);
    stub->async()->WatchJob(&context_, &request_, this);
    StartRead(&response_);
    StartCall();
  }
  void OnReadDone(bool ok) override {
    if (!ok) return;
    if (!first_) ++*opened_;
    first_ = true;
    StartRead(&response_);
  }
  void OnDone(const grpc::Status& s) override {
    if (s.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED) {
      ++*refused_;
      std::lock_guard<std::mutex> lock(mu_);
      message_ = s.error_message();
    }
    ++*ended_;
  }
  void Cancel() { context_.TryCancel(); }
  std::string message() {
    std::lock_guard<std::mutex> lock(mu_);
    return message_;
  }

 private:
  grpc::ClientContext context_;
  v1::WatchJobRequest request_;
  v1::WatchJobResponse response_;
  std::atomic<int>* opened_;
  std::atomic<int>* refused_;
  std::atomic<int>* ended_;
  bool first_ = false;
  std::mutex mu_;
  std::string message_;
};

TEST_F(ServiceTest, AThousandWatchesAreBoundedAndCostNoThreadEach) {
  // No worker here: the watched job stays queued until it is cancelled, however fast or
  // slow the machine (a long job ahead of it once finished early and ended the watches).
  options_.local_workers = false;
  StartServer();
  const std::string path = WritePhantom(dir_.path(), "w", 32, 6);
  auto digest = client_->Upload(path);
  ASSERT_TRUE(digest.ok());
  v1::CreateJobRequest r = UploadRequest(*digest, std::filesystem::path(path).filename(), "w");
  r.mutable_parameters()->set_extract(true);
  auto job = client_->CreateJob(r);
  ASSERT_TRUE(job.ok());
  const int threads_before = Threads();
  std::atomic<int> opened{0}, refused{0}, ended{0};
  std::vector<std::unique_ptr<WatchReader>> watches;
  for (int i = 0; i < 1000; ++i) {
    watches.push_back(
        std::make_unique<WatchReader>(client_->jobs(), job->name(), "", &opened, &refused, &ended));
  }
  // A bound on the waits below, not a measure: a loaded machine (the suite runs two tests
  // at a time beside the long job) once took over a minute to open them all.
  const absl::Time deadline = absl::Now() + absl::Seconds(180);
  while (opened + refused < 1000 && absl::Now() < deadline) absl::SleepFor(absl::Milliseconds(20));
  EXPECT_EQ(opened.load(), 256) << "the default limit per client";
  EXPECT_EQ(refused.load(), 744);
  for (auto& w : watches) {
    if (!w->message().empty()) {
      EXPECT_THAT(w->message(), HasSubstr("--max_watch_streams_per_client"));
      break;
    }
  }
  const int threads_during = Threads();
  EXPECT_LT(threads_during - threads_before, 64)
      << threads_before << " threads before, " << threads_during << " with 256 watches open";
  // Closed watches give their places back.
  for (auto& w : watches) w->Cancel();
  while (ended < 1000 && absl::Now() < deadline) absl::SleepFor(absl::Milliseconds(20));
  watches.clear();
  opened = refused = ended = 0;
  for (int i = 0; i < 10; ++i) {
    watches.push_back(
        std::make_unique<WatchReader>(client_->jobs(), job->name(), "", &opened, &refused, &ended));
  }
  while (opened < 10 && absl::Now() < deadline) absl::SleepFor(absl::Milliseconds(20));
  EXPECT_EQ(opened.load(), 10);
  for (auto& w : watches) w->Cancel();
  while (ended < 10 && absl::Now() < deadline) absl::SleepFor(absl::Milliseconds(20));
  EXPECT_TRUE(client_->CancelJob(job->name()).ok());
}

// ---------------------------------------------------------------------------------------
// Tenants

class TenantTest : public ServiceTest {
 protected:
  void SetUp() override {
    ServiceTest::SetUp();
    std::ofstream(dir_.File("tokens")) << "# lab tokens\n"
                                       << "token-of-alice-0123456789 alice\n"
                                       << "token-of-bob-0123456789 bob  # the other lab\n";
    options_.auth_token_file = dir_.File("tokens");
  }

  std::unique_ptr<client::SheetmeshClient> As(const std::string& token) {
    client::ClientOptions co;
    co.address = absl::StrCat("127.0.0.1:", server_->port());
    co.auth_token = token;
    auto c = client::SheetmeshClient::Connect(co);
    EXPECT_TRUE(c.ok()) << c.status();
    return std::move(*c);
  }
};

TEST_F(TenantTest, OneTenantCannotSeeOrUseAnothersJobsUploadsOrArtifacts) {
  StartServer();
  auto alice = As("token-of-alice-0123456789");
  auto bob = As("token-of-bob-0123456789");
  const std::string path = WritePhantom(dir_.path(), "shared", 32, 8);
  auto digest = alice->Upload(path);
  ASSERT_TRUE(digest.ok()) << digest.status();
  // Without the extraction: 32³ holds no piece of its M.
  auto request = [&](const v1::Digest& d, const std::string& id) {
    v1::CreateJobRequest r = UploadRequest(d, std::filesystem::path(path).filename().string(), id);
    r.mutable_parameters()->set_extract(false);
    return r;
  };
  auto job = alice->CreateJob(request(*digest, "same-id"));
  ASSERT_TRUE(job.ok()) << job.status();
  auto done = alice->Watch(job->name(), {});
  ASSERT_TRUE(done.ok());
  ASSERT_EQ(done->state(), v1::SUCCEEDED);
  EXPECT_EQ(done->tenant(), "alice");
  ASSERT_FALSE(done->artifacts().empty());
  const v1::Digest artifact = done->artifacts(0).digest();

  // Bob sees none of it: not in lists, not by name, not by digest.
  v1::ListJobsRequest lr;
  auto list = bob->ListJobs(lr);
  ASSERT_TRUE(list.ok());
  EXPECT_EQ(list->jobs_size(), 0);
  EXPECT_EQ(bob->GetJob(job->name()).status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(bob->CancelJob(job->name()).status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(bob->DeleteJob(job->name()).code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(bob->Watch(job->name(), {}).status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(bob->Download(artifact, dir_.File("stolen")).code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(Missing(*bob, *digest).size(), 1u) << "another tenant's upload is missing to bob";
  auto borrowed = bob->CreateJob(request(*digest, "borrow"));
  EXPECT_EQ(borrowed.status().code(), absl::StatusCode::kFailedPrecondition);

  // Bob uploads the same bytes himself (they must come) and uses his own request id space.
  auto his = bob->Upload(path);
  ASSERT_TRUE(his.ok());
  EXPECT_TRUE(Missing(*bob, *digest).empty());
  auto bobs_job = bob->CreateJob(request(*his, "same-id"));
  ASSERT_TRUE(bobs_job.ok());
  EXPECT_NE(bobs_job->name(), job->name());
  EXPECT_TRUE(bobs_job->cached_from().empty()) << "results are not shared between tenants";
  auto bobs_done = bob->Watch(bobs_job->name(), {});
  ASSERT_TRUE(bobs_done.ok());
  ASSERT_EQ(bobs_done->state(), v1::SUCCEEDED);
  EXPECT_TRUE(bob->Download(bobs_done->artifacts(0).digest(), dir_.File("his")).ok());
  // Alice still has exactly her one job.
  auto alices = alice->ListJobs(lr);
  ASSERT_TRUE(alices.ok());
  ASSERT_EQ(alices->jobs_size(), 1);
  EXPECT_EQ(alices->jobs(0).name(), job->name());
  // Without a token, or with one the file does not hold: UNAUTHENTICATED.
  EXPECT_EQ(As("")->ListJobs(lr).status().code(), absl::StatusCode::kUnauthenticated);
  EXPECT_EQ(As("token-of-nobody")->ListJobs(lr).status().code(),
            absl::StatusCode::kUnauthenticated);
  EXPECT_EQ(*As("")->Health(), "SERVING") << "health needs no token";
}

// One round of server reflection's list_services, by hand (its protos are not installed):
// the bytes of the answer, or the call's status.
grpc::Status ListServicesByReflection(int port, const std::string& token, std::string* answer) {
  auto channel =
      grpc::CreateChannel(absl::StrCat("127.0.0.1:", port), grpc::InsecureChannelCredentials());
  grpc::GenericStub stub(channel);
  grpc::CompletionQueue cq;
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  if (!token.empty()) ctx.AddMetadata("authorization", "Bearer " + token);
  auto call =
      stub.PrepareCall(&ctx, "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo", &cq);
  void* tag;
  bool ok;
  auto step = [&](int t) {
    cq.Next(&tag, &ok);
    return ok && tag == reinterpret_cast<void*>(t);
  };
  call->StartCall(reinterpret_cast<void*>(1));
  step(1);
  const std::string request("\x3a\x00", 2);  // ServerReflectionRequest{list_services: ""}
  grpc::Slice slice(request);
  grpc::ByteBuffer out(&slice, 1);
  call->Write(out, reinterpret_cast<void*>(2));
  step(2);
  grpc::ByteBuffer in;
  call->Read(&in, reinterpret_cast<void*>(3));
  if (step(3)) {
    std::vector<grpc::Slice> slices;
    in.Dump(&slices);
    for (const grpc::Slice& s : slices)
      answer->append(reinterpret_cast<const char*>(s.begin()), s.size());
  }
  call->WritesDone(reinterpret_cast<void*>(4));
  step(4);
  grpc::Status status;
  call->Finish(&status, reinterpret_cast<void*>(5));
  step(5);
  return status;
}

TEST_F(TenantTest, ReflectionNeedsAToken) {
  StartServer();
  std::string answer;
  EXPECT_FALSE(ListServicesByReflection(server_->port(), "", &answer).ok());
  EXPECT_THAT(answer, ::testing::Not(HasSubstr("sheetmesh.v1"))) << "nothing answered";
  answer.clear();
  EXPECT_TRUE(ListServicesByReflection(server_->port(), "token-of-bob-0123456789", &answer).ok());
  EXPECT_THAT(answer, HasSubstr("sheetmesh.v1.JobService"));
}

TEST_F(TenantTest, AMalformedTokenFileNamesTheLine) {
  std::ofstream(dir_.File("bad-tokens")) << "good-token-12345 alice\nsecond-token ../evil\n";
  options_.auth_token_file = dir_.File("bad-tokens");
  auto s = server::Server::Start(options_);
  EXPECT_EQ(s.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.status().message(), HasSubstr("line 2"));
  EXPECT_THAT(s.status().message(), HasSubstr("../evil"));
}

// ---------------------------------------------------------------------------------------
// Retention and health

TEST_F(ServiceTest, RetentionCollectsWhatNoJobNamesAndADryRunOnlyLists) {
  options_.blob_retention = absl::Milliseconds(1);
  options_.gc_dry_run = true;
  StartServer();
  const std::string path = WritePhantom(dir_.path(), "kept", 32, 1);
  auto digest = client_->Upload(path);
  ASSERT_TRUE(digest.ok());
  auto keep = client_->CreateJob(
      UploadRequest(*digest, std::filesystem::path(path).filename().string(), "keep"));
  ASSERT_TRUE(keep.ok());
  v1::CreateJobRequest other =
      UploadRequest(*digest, std::filesystem::path(path).filename().string(), "drop");
  other.mutable_parameters()->set_r(4);
  auto drop = client_->CreateJob(other);
  ASSERT_TRUE(drop.ok());
  const v1::Job kept = WaitFinished(keep->name()), dropped = WaitFinished(drop->name());
  ASSERT_EQ(kept.state(), v1::SUCCEEDED);
  ASSERT_EQ(dropped.state(), v1::SUCCEEDED);
  ASSERT_TRUE(client_->DeleteJob(drop->name()).ok());
  absl::SleepFor(absl::Seconds(1.1));  // older than the retention (file times are seconds)
  // The dry run lists the deleted job's own artifacts, and removes nothing.
  auto listing = server_->CollectNow();
  ASSERT_TRUE(listing.ok()) << listing.status();
  int only_dropped = 0;
  for (const v1::Artifact& a : dropped.artifacts()) {
    bool shared = false;
    for (const v1::Artifact& k : kept.artifacts()) shared |= k.digest().hash() == a.digest().hash();
    if (shared) continue;
    ++only_dropped;
    EXPECT_THAT(*listing, HasSubstr("would remove " + a.digest().hash())) << a.name();
    EXPECT_TRUE(client_->Download(a.digest(), dir_.File("dry")).ok());
  }
  ASSERT_GT(only_dropped, 0);
  EXPECT_THAT(*listing, ::testing::Not(HasSubstr(digest->hash()))) << "a job still names it";
  // For real: gone, while what the kept job names stays.
  server_->Shutdown(absl::Seconds(1));
  options_.gc_dry_run = false;
  auto once = server::CollectOnce(options_);
  ASSERT_TRUE(once.ok()) << once.status();
  EXPECT_THAT(*once, HasSubstr(absl::StrCat("removed ", only_dropped, " blobs")));
  StartServer();
  for (const v1::Artifact& a : kept.artifacts()) {
    EXPECT_TRUE(client_->Download(a.digest(), dir_.File("k")).ok()) << a.name();
  }
  for (const v1::Artifact& a : dropped.artifacts()) {
    bool shared = false;
    for (const v1::Artifact& k : kept.artifacts()) shared |= k.digest().hash() == a.digest().hash();
    if (!shared) {
      EXPECT_EQ(client_->Download(a.digest(), dir_.File("d")).code(), absl::StatusCode::kNotFound);
    }
  }
}

TEST_F(ServiceTest, HealthIsNotServingWhenTheDiskIsFull) {
  options_.min_free_disk_bytes = int64_t{1} << 60;  // more than any disk has
  StartServer();
  const absl::Time deadline = absl::Now() + absl::Seconds(10);
  while (server_->not_serving_reason().empty() && absl::Now() < deadline) {
    absl::SleepFor(absl::Milliseconds(50));
  }
  EXPECT_THAT(server_->not_serving_reason(), HasSubstr("--min_free_disk_mb"));
  EXPECT_EQ(*client_->Health(), "NOT_SERVING");
}

}  // namespace
}  // namespace sheetmesh::testing
