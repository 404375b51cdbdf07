// Hardening over the real gRPC stack: the audit's bad inputs and faults as one table (each
// case its input, the exact status code, the words the message must hold), every case run
// while a good job runs beside them; then the faults that need their own server: crashing
// job processes, stalled and abandoned uploads, a thousand watches, two tenants, retention
// and health. After every case the server still answers and the good job succeeds.
#include <gmock/gmock.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <functional>
#include <thread>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/file_util.h"
#include "common/sha256.h"
#include "tests/server/service_fixture.h"
#include "tests/testing/bad_volumes.h"
#include "worker/pipeline/volume/nrrd_io.h"

namespace sheetmesh::testing {
namespace {

using ::testing::HasSubstr;

// One bad input: what it is, how it reaches the server, and what the server must answer.
struct BadCase {
  std::string name;
  // Writes the input into `dir` and returns its path.
  std::function<std::string(const std::string& dir)> make;
  bool by_path = false;     // named under the allowed root instead of uploaded
  std::string file_name;    // as uploaded ("" : the file's own name)
  std::string volume_path;  // a path to name as it is (the file is not used)
  std::function<void(v1::CreateJobRequest&)> edit;  // parameters and the like
  // Refused by CreateJob with this code, or accepted and FAILED with it.
  bool refused_at_create = false;
  absl::StatusCode code;
  std::vector<std::string> words;  // the message holds each
};

std::string Write(const std::string& path, const std::string& bytes) {
  EXPECT_TRUE(WriteFileAtomically(path, bytes).ok()) << path;
  return path;
}

std::vector<BadCase> Cases() {
  std::vector<BadCase> c;
  auto phantom = [](const std::string& d) { return WritePhantom(d, "p", 32, 5); };
  c.push_back(
      {"passwd_header_uploaded",
       [](const std::string& d) { return Write(d + "/x.nhdr", HeaderNaming("/etc/passwd")); },
       false,
       "x.nhdr",
       "",
       nullptr,
       false,
       absl::StatusCode::kPermissionDenied,
       {"data file", "/etc/passwd"}});
  c.push_back(
      {"passwd_header_referenced",
       [](const std::string& d) { return Write(d + "/x.nhdr", HeaderNaming("/etc/passwd")); },
       true,
       "",
       "",
       nullptr,
       false,
       absl::StatusCode::kPermissionDenied,
       {"/etc/passwd"}});
  c.push_back({"header_naming_a_link_out",
               [](const std::string& d) {
                 std::filesystem::create_symlink("/etc/passwd", d + "/out.raw");
                 return Write(d + "/l.nhdr", HeaderNaming("out.raw"));
               },
               true,
               "",
               "",
               nullptr,
               false,
               absl::StatusCode::kPermissionDenied,
               {"out.raw"}});
  c.push_back({"cut_vdb",
               [](const std::string& d) {
                 const std::string p = d + "/t.vdb";
                 EXPECT_TRUE(WriteVolume(p, SheetVolume({48, 40, 32})).ok());
                 CutFile(p, 0.4);
                 return p;
               },
               false,
               "t.vdb",
               "",
               nullptr,
               false,
               absl::StatusCode::kInvalidArgument,
               {"t.vdb"}});
  // 60000^2 fits the job's memory: the strip the header promises is not in the file.
  // 200000^2 does not: refused before anything is allocated.
  for (const auto& [side, code, word] :
       std::vector<std::tuple<uint32_t, absl::StatusCode, std::string>>{
           {60000u, absl::StatusCode::kInvalidArgument, "strip 0"},
           {200000u, absl::StatusCode::kResourceExhausted, "200000"}}) {
    c.push_back({absl::StrCat("tiff_claiming_", side),
                 [side = side](const std::string& d) {
                   return Write(absl::StrCat(d, "/bomb", side, ".tif"), TiffClaiming(side, side));
                 },
                 false,
                 absl::StrCat("bomb", side, ".tif"),
                 "",
                 nullptr,
                 false,
                 code,
                 {absl::StrCat("bomb", side, ".tif"), word}});
  }
  c.push_back({"cut_multipage_tiff",
               [](const std::string& d) {
                 const std::string p = d + "/stack.tif";
                 EXPECT_TRUE(WriteVolume(p, SheetVolume({40, 30, 20})).ok());
                 CutFile(p, 0.5);
                 return p;
               },
               false,
               "stack.tif",
               "",
               nullptr,
               false,
               absl::StatusCode::kInvalidArgument,
               {"stack.tif", "page"}});
  c.push_back(
      {"raw_shorter_than_its_name",
       [](const std::string& d) { return Write(d + "/s_32x32x32_u8.raw", std::string(100, 1)); },
       false,
       "s_32x32x32_u8.raw",
       "",
       nullptr,
       false,
       absl::StatusCode::kInvalidArgument,
       {"32768", "100"}});
  c.push_back(
      {"raw_type_i7",
       [](const std::string& d) { return Write(d + "/v_4x4x4_i7.raw", std::string(64, 1)); },
       false,
       "v_4x4x4_i7.raw",
       "",
       nullptr,
       false,
       absl::StatusCode::kInvalidArgument,
       {"i7"}});
  c.push_back(
      {"nrrd_gzip_cut",
       [](const std::string& d) {
         const std::string p = d + "/g.nrrd";
         auto sink = CreateNrrdWriter(p, SheetVolume({32, 32, 16}).info, NrrdEncoding::kGzip);
         EXPECT_TRUE(sink.ok());
         EXPECT_TRUE(WriteDense(SheetVolume({32, 32, 16}), **sink).ok());
         CutFile(p, 0.6);
         return p;
       },
       false,
       "g.nrrd",
       "",
       nullptr,
       false,
       absl::StatusCode::kInvalidArgument,
       {"g.nrrd"}});
  c.push_back({"nrrd_sizes_beyond_the_file",
               [](const std::string& d) {
                 return Write(d + "/h.nrrd",
                              "NRRD0004\ntype: float\ndimension: 3\nsizes: 100000 100000 100000\n"
                              "encoding: raw\n\nxxxx");
               },
               false,
               "h.nrrd",
               "",
               nullptr,
               false,
               absl::StatusCode::kResourceExhausted,
               {"100000"}});
  c.push_back({"grayscale_float_without_phase",
               [](const std::string& d) { return WriteGrayscale(d, 24); },
               false,
               "",
               "",
               nullptr,
               false,
               absl::StatusCode::kInvalidArgument,
               {"input.labels", "input.window"}});
  c.push_back({"nan_volume_window",
               [](const std::string& d) {
                 const std::string p = absl::StrCat(d, "/allnan_8x8x8_f32.raw");
                 std::vector<float> v(512, std::numeric_limits<float>::quiet_NaN());
                 std::ofstream(p, std::ios::binary)
                     .write(reinterpret_cast<const char*>(v.data()), v.size() * 4);
                 return p;
               },
               false,
               "",
               "",
               [](v1::CreateJobRequest& r) {
                 r.mutable_parameters()->add_window(-1e30);
                 r.mutable_parameters()->add_window(1e30);
               },
               false,
               absl::StatusCode::kInvalidArgument,
               {"allnan"}});
  for (const char* bad : {"../p_32x32x32_u8.raw", "/", "..", "a/b.raw"}) {
    c.push_back({absl::StrCat("file_name ", bad),
                 phantom,
                 false,
                 bad,
                 "",
                 nullptr,
                 true,
                 absl::StatusCode::kInvalidArgument,
                 {"input.file_name"}});
  }
  c.push_back({"path_outside_the_roots",
               nullptr,
               true,
               "",
               "/etc/passwd",
               nullptr,
               true,
               absl::StatusCode::kPermissionDenied,
               {"/etc/passwd"}});
  c.push_back({"path_with_nul",
               nullptr,
               true,
               "",
               std::string("/etc/passwd\0.raw", 16),
               nullptr,
               true,
               absl::StatusCode::kInvalidArgument,
               {"NUL"}});
  c.push_back(
      {"refine_close_radius_100000",
       phantom,
       false,
       "",
       "",
       [](v1::CreateJobRequest& r) { r.mutable_parameters()->set_refine_close_radius(100000); },
       true,
       absl::StatusCode::kInvalidArgument,
       {"refine_close_radius", "100000"}});
  c.push_back(
      {"detect_rounds_2^31-1",
       phantom,
       false,
       "",
       "",
       [](v1::CreateJobRequest& r) { r.mutable_parameters()->set_detect_rounds(2147483647); },
       true,
       absl::StatusCode::kInvalidArgument,
       {"detect_rounds", "2147483647"}});
  c.push_back({"tet_max_volume_1e-12",
               phantom,
               false,
               "",
               "",
               [](v1::CreateJobRequest& r) {
                 r.mutable_parameters()->set_volume_mesh(true);
                 r.mutable_parameters()->set_tet_max_volume(1e-12);
               },
               false,
               absl::StatusCode::kInvalidArgument,
               {"tet.max_volume", "1e-12"}});
  c.push_back({"time_limit_reached",
               phantom,
               false,
               "",
               "",
               [](v1::CreateJobRequest& r) {
                 r.mutable_parameters()->set_extract(true);
                 r.mutable_parameters()->set_time_limit_seconds(0.05);
               },
               false,
               absl::StatusCode::kDeadlineExceeded,
               {"time limit"}});
  c.push_back({"request_id_with_a_control_character",
               phantom,
               false,
               "",
               "",
               [](v1::CreateJobRequest& r) { r.set_request_id("a\nb"); },
               true,
               absl::StatusCode::kInvalidArgument,
               {"request_id"}});
  c.push_back({"digest_not_stored",
               phantom,
               false,
               "",
               "",
               [](v1::CreateJobRequest& r) {
                 r.mutable_input()->mutable_volume_digest()->set_hash(std::string(64, 'a'));
               },
               true,
               absl::StatusCode::kFailedPrecondition,
               {"upload it first"}});
  c.push_back(
      {"digest_malformed",
       phantom,
       false,
       "",
       "",
       [](v1::CreateJobRequest& r) { r.mutable_input()->mutable_volume_digest()->set_hash("XYZ"); },
       true,
       absl::StatusCode::kInvalidArgument,
       {"XYZ"}});
  return c;
}

class HardeningTest : public ServiceTest {
 protected:
  // A job that succeeds, to run beside the bad ones.
  std::string StartGoodJob(const std::string& id) {
    const std::string path = WritePhantom(dir_.path(), "good", 48, 3);
    auto digest = client_->Upload(path);
    EXPECT_TRUE(digest.ok()) << digest.status();
    v1::CreateJobRequest r = UploadRequest(*digest, std::filesystem::path(path).filename(), id);
    r.mutable_parameters()->set_extract(true);
    auto job = client_->CreateJob(r);
    EXPECT_TRUE(job.ok()) << job.status();
    return job.ok() ? job->name() : "";
  }

  void ExpectServing() {
    auto health = client_->Health();
    ASSERT_TRUE(health.ok()) << health.status();
    EXPECT_EQ(*health, "SERVING");
  }
};

TEST_F(HardeningTest, EveryBadInputGetsItsCodeAndAMessageNamingIt) {
  StartServer();
  const pid_t pid = ::getpid();
  const std::string good = StartGoodJob("good-beside-the-bad");
  int n = 0;
  for (const BadCase& c : Cases()) {
    SCOPED_TRACE(c.name);
    const std::string dir = dir_.File(absl::StrCat("case", ++n));
    std::filesystem::create_directories(dir);
    const std::string root_dir = absl::StrCat(options_.allowed_roots[0], "/case", n);
    std::filesystem::create_directories(root_dir);
    v1::CreateJobRequest r;
    r.set_request_id(absl::StrCat("bad-", n));
    std::string path;
    if (c.make) path = c.make(c.by_path ? root_dir : dir);
    if (!c.volume_path.empty()) {
      r.mutable_input()->set_volume_path(c.volume_path);
    } else if (c.by_path) {
      r.mutable_input()->set_volume_path(path);
    } else {
      auto digest = client_->Upload(path);
      ASSERT_TRUE(digest.ok()) << digest.status();
      *r.mutable_input()->mutable_volume_digest() = *digest;
      r.mutable_input()->set_file_name(
          c.file_name.empty() ? std::filesystem::path(path).filename().string() : c.file_name);
    }
    if (c.edit) c.edit(r);
    auto job = client_->CreateJob(r);
    if (c.refused_at_create) {
      ASSERT_FALSE(job.ok()) << "accepted";
      EXPECT_EQ(job.status().code(), c.code) << job.status();
      for (const std::string& w : c.words) EXPECT_THAT(job.status().message(), HasSubstr(w));
    } else {
      ASSERT_TRUE(job.ok()) << job.status();
      const v1::Job done = WaitFinished(job->name());
      EXPECT_EQ(done.state(), v1::FAILED);
      EXPECT_EQ(done.error().code(), static_cast<int>(c.code)) << done.error().message();
      for (const std::string& w : c.words) EXPECT_THAT(done.error().message(), HasSubstr(w));
      EXPECT_EQ(done.attempts(), 1) << "a bad input is not retried";
    }
    ExpectServing();
  }
  EXPECT_EQ(::getpid(), pid);
  const v1::Job done = WaitFinished(good);
  EXPECT_EQ(done.state(), v1::SUCCEEDED) << done.error().message();
}

// The job program: a wrapper of the real one that, for some inputs, dies as a pipeline
// might (a signal, an abort); others run as usual.
std::string WriteCrashingJobProgram(const std::string& dir) {
  const std::string path = dir + "/crashing-job-program";
  std::ofstream(path) << "#!/bin/sh\n"
                      << "spec=\"$2\"\n"
                      << "grep -q crash-segv \"$spec\" && kill -SEGV $$\n"
                      << "grep -q crash-bus \"$spec\" && kill -BUS $$\n"
                      << "grep -q crash-abort \"$spec\" && kill -ABRT $$\n"
                      << "exec " << SHEETMESH_SERVER_BIN << " \"$@\"\n";
  std::filesystem::permissions(path, std::filesystem::perms::owner_all);
  return path;
}

TEST_F(HardeningTest, AJobThatCrashesFailsAloneNamingTheSignalAndIsNotRetried) {
  options_.job_program = WriteCrashingJobProgram(dir_.path());
  StartServer();
  const std::string good = StartGoodJob("good");
  for (const auto& [name, signal] : std::vector<std::pair<std::string, std::string>>{
           {"crash-segv", "SIGSEGV"}, {"crash-bus", "SIGBUS"}, {"crash-abort", "SIGABRT"}}) {
    SCOPED_TRACE(name);
    const std::string path = WritePhantom(dir_.path(), name, 32, 9);
    auto digest = client_->Upload(path);
    ASSERT_TRUE(digest.ok());
    auto job = client_->CreateJob(
        UploadRequest(*digest, std::filesystem::path(path).filename().string(), name));
    ASSERT_TRUE(job.ok()) << job.status();
    const v1::Job done = WaitFinished(job->name());
    EXPECT_EQ(done.state(), v1::FAILED);
    EXPECT_EQ(done.error().code(), static_cast<int>(absl::StatusCode::kInternal));
    EXPECT_THAT(done.error().message(), HasSubstr(signal));
    EXPECT_EQ(done.attempts(), 1);
  }
  EXPECT_EQ(WaitFinished(good).state(), v1::SUCCEEDED);
  ExpectServing();
}

TEST_F(HardeningTest, AJobPastItsMemoryLimitFailsResourceExhausted) {
  options_.job_limits.memory_bytes = uint64_t{600} << 20;
  StartServer();
  // 1024 x 1024 x 512 voxels: half a GiB to read, more to analyse.
  const std::string path = options_.allowed_roots[0] + "/big_1024x1024x512_u8.raw";
  std::ofstream(path).close();
  std::filesystem::resize_file(path, int64_t{1024} * 1024 * 512);
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    for (int z = 0; z < 512; z += 8) {  // a sheet every 8 slices
      f.seekp(int64_t{z} * 1024 * 1024);
      const std::string plane(1024 * 1024, 1);
      f.write(plane.data(), plane.size());
    }
  }
  v1::CreateJobRequest r;
  r.set_request_id("hog");
  r.mutable_input()->set_volume_path(path);
  auto job = client_->CreateJob(r);
  ASSERT_TRUE(job.ok()) << job.status();
  const v1::Job done = WaitFinished(job->name());
  EXPECT_EQ(done.state(), v1::FAILED);
  EXPECT_EQ(done.error().code(), static_cast<int>(absl::StatusCode::kResourceExhausted))
      << done.error().message();
  EXPECT_THAT(done.error().message(), HasSubstr("memory"));
  ExpectServing();
}

TEST_F(HardeningTest, AReferencedVolumeTruncatedWhileReadFailsTheJobNotTheServer) {
  StartServer();
  const std::string path = options_.allowed_roots[0] + "/race_256x256x256_u8.raw";
  {
    std::string bytes(int64_t{256} * 256 * 256, 0);
    for (int64_t z = 0; z < 256; ++z) bytes[(z * 256 + 128) * 256 + z % 256] = 1;
    ASSERT_TRUE(WriteFileAtomically(path, bytes).ok());
  }
  for (int round = 0; round < 3; ++round) {
    v1::CreateJobRequest r;
    r.set_request_id(absl::StrCat("race-", round));
    r.set_no_cache(true);
    r.mutable_input()->set_volume_path(path);
    auto job = client_->CreateJob(r);
    ASSERT_TRUE(job.ok()) << job.status();
    WaitRunning(*client_, job->name(), 0);
    std::filesystem::resize_file(path, int64_t{256} * 256 * 40);
    const v1::Job done = WaitFinished(job->name());
    // Read before the cut it may succeed; after, it fails as bad input. Never a signal.
    if (done.state() == v1::FAILED) {
      EXPECT_EQ(done.error().code(), static_cast<int>(absl::StatusCode::kInvalidArgument))
          << done.error().message();
      EXPECT_THAT(done.error().message(), ::testing::Not(HasSubstr("SIG")));
    } else {
      EXPECT_EQ(done.state(), v1::SUCCEEDED);
    }
    std::filesystem::resize_file(path, int64_t{256} * 256 * 256);
  }
  ExpectServing();
}

}  // namespace
}  // namespace sheetmesh::testing
