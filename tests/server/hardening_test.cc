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

using Maker = std::function<std::string(const std::string& dir)>;
using Edit = std::function<void(v1::CreateJobRequest&)>;

// An upload (as `file_name`, "" for the file's own) that is accepted and FAILS with `code`.
BadCase Fails(std::string name, Maker make, std::string file_name, absl::StatusCode code,
              std::vector<std::string> words, Edit edit = nullptr) {
  return {std::move(name), std::move(make), false, std::move(file_name), "",
          std::move(edit), false,           code,  std::move(words)};
}
// The same for a file named by path under the allowed root.
BadCase FailsByPath(std::string name, Maker make, absl::StatusCode code,
                    std::vector<std::string> words) {
  return {std::move(name), std::move(make), true, "", "", nullptr, false, code, std::move(words)};
}
// A request CreateJob refuses with `code`.
BadCase Refused(std::string name, Maker make, absl::StatusCode code, std::vector<std::string> words,
                Edit edit, std::string file_name = "") {
  return {std::move(name),
          std::move(make),
          false,
          std::move(file_name),
          "",
          std::move(edit),
          true,
          code,
          std::move(words)};
}
// A volume_path CreateJob refuses with `code`.
BadCase RefusedPath(std::string name, std::string path, absl::StatusCode code,
                    std::vector<std::string> words) {
  return {std::move(name), nullptr, true, "", std::move(path), nullptr, true, code,
          std::move(words)};
}

std::string WriteCut(const std::string& path, const DenseVolume& v, double keep) {
  EXPECT_TRUE(WriteVolume(path, v).ok()) << path;
  CutFile(path, keep);
  return path;
}

std::vector<BadCase> Cases() {
  using absl::StatusCode;
  const Maker phantom = [](const std::string& d) { return WritePhantom(d, "p", 32, 5); };
  const Maker passwd = [](const std::string& d) {
    return Write(d + "/x.nhdr", HeaderNaming("/etc/passwd"));
  };
  std::vector<BadCase> c;
  c.push_back(Fails("passwd_header_uploaded", passwd, "x.nhdr", StatusCode::kPermissionDenied,
                    {"data file", "/etc/passwd"}));
  c.push_back(FailsByPath("passwd_header_referenced", passwd, StatusCode::kPermissionDenied,
                          {"/etc/passwd"}));
  c.push_back(FailsByPath("header_naming_a_link_out",
                          [](const std::string& d) {
                            std::filesystem::create_symlink("/etc/passwd", d + "/out.raw");
                            return Write(d + "/l.nhdr", HeaderNaming("out.raw"));
                          },
                          StatusCode::kPermissionDenied, {"out.raw"}));
  c.push_back(Fails("cut_vdb",
                    [](const std::string& d) {
                      return WriteCut(d + "/t.vdb", SheetVolume({48, 40, 32}), 0.4);
                    },
                    "t.vdb", StatusCode::kInvalidArgument, {"t.vdb"}));
  // 60000^2 fits the job's memory: the strip the header promises is not in the file.
  // 200000^2 does not: refused before anything is allocated.
  c.push_back(Fails(
      "tiff_claiming_60000",
      [](const std::string& d) { return Write(d + "/bomb60000.tif", TiffClaiming(60000, 60000)); },
      "", StatusCode::kInvalidArgument, {"bomb60000.tif", "strip 0"}));
  c.push_back(Fails("tiff_claiming_200000",
                    [](const std::string& d) {
                      return Write(d + "/bomb200000.tif", TiffClaiming(200000, 200000));
                    },
                    "", StatusCode::kResourceExhausted, {"bomb200000.tif", "200000"}));
  c.push_back(Fails("cut_multipage_tiff",
                    [](const std::string& d) {
                      return WriteCut(d + "/stack.tif", SheetVolume({40, 30, 20}), 0.5);
                    },
                    "", StatusCode::kInvalidArgument, {"stack.tif", "page"}));
  c.push_back(Fails(
      "raw_shorter_than_its_name",
      [](const std::string& d) { return Write(d + "/s_32x32x32_u8.raw", std::string(100, 1)); }, "",
      StatusCode::kInvalidArgument, {"32768", "100"}));
  c.push_back(
      Fails("raw_type_i7",
            [](const std::string& d) { return Write(d + "/v_4x4x4_i7.raw", std::string(64, 1)); },
            "", StatusCode::kInvalidArgument, {"i7"}));
  c.push_back(
      Fails("nrrd_gzip_cut",
            [](const std::string& d) {
              const std::string p = d + "/g.nrrd";
              auto sink = CreateNrrdWriter(p, SheetVolume({32, 32, 16}).info, NrrdEncoding::kGzip);
              EXPECT_TRUE(sink.ok() && WriteDense(SheetVolume({32, 32, 16}), **sink).ok());
              CutFile(p, 0.6);
              return p;
            },
            "", StatusCode::kInvalidArgument, {"g.nrrd"}));
  c.push_back(Fails("nrrd_sizes_beyond_the_file",
                    [](const std::string& d) {
                      return Write(
                          d + "/h.nrrd",
                          "NRRD0004\ntype: float\ndimension: 3\nsizes: 100000 100000 100000\n"
                          "encoding: raw\n\nxxxx");
                    },
                    "", StatusCode::kResourceExhausted, {"100000"}));
  c.push_back(Fails("grayscale_float_without_phase",
                    [](const std::string& d) { return WriteGrayscale(d, 24); }, "",
                    StatusCode::kInvalidArgument, {"--grey", "input.labels", "input.window"}));
  c.push_back(Fails(
      "nan_volume_window",
      [](const std::string& d) {
        const std::string p = d + "/allnan_8x8x8_f32.raw";
        std::vector<float> v(512, std::numeric_limits<float>::quiet_NaN());
        std::ofstream(p, std::ios::binary).write(reinterpret_cast<const char*>(v.data()), 2048);
        return p;
      },
      "", StatusCode::kInvalidArgument, {"allnan"},
      [](v1::CreateJobRequest& r) {
        r.mutable_parameters()->add_window(-1e30);
        r.mutable_parameters()->add_window(1e30);
      }));
  for (const char* bad : {"../p_32x32x32_u8.raw", "/", "..", "a/b.raw"}) {
    c.push_back(Refused(absl::StrCat("file_name ", bad), phantom, StatusCode::kInvalidArgument,
                        {"input.file_name"}, nullptr, bad));
  }
  c.push_back(RefusedPath("path_outside_the_roots", "/etc/passwd", StatusCode::kPermissionDenied,
                          {"/etc/passwd"}));
  c.push_back(RefusedPath("path_with_nul", std::string("/etc/passwd\0.raw", 16),
                          StatusCode::kInvalidArgument, {"NUL"}));
  c.push_back(Refused("refine_close_radius_100000", phantom, StatusCode::kInvalidArgument,
                      {"refine_close_radius", "100000"}, [](v1::CreateJobRequest& r) {
                        r.mutable_parameters()->set_refine_close_radius(100000);
                      }));
  c.push_back(Refused("detect_rounds_2^31-1", phantom, StatusCode::kInvalidArgument,
                      {"detect_rounds", "2147483647"}, [](v1::CreateJobRequest& r) {
                        r.mutable_parameters()->set_detect_rounds(2147483647);
                      }));
  c.push_back(Fails("tet_max_volume_1e-12", phantom, "", StatusCode::kInvalidArgument,
                    {"tet.max_volume", "1e-12"}, [](v1::CreateJobRequest& r) {
                      r.mutable_parameters()->set_volume_mesh(true);
                      r.mutable_parameters()->set_tet_max_volume(1e-12);
                    }));
  c.push_back(Fails("time_limit_reached", phantom, "", StatusCode::kDeadlineExceeded,
                    {"time limit"}, [](v1::CreateJobRequest& r) {
                      r.mutable_parameters()->set_extract(true);
                      r.mutable_parameters()->set_time_limit_seconds(0.05);
                    }));
  // Hardening, third round: this was UNKNOWN (an uncaught nlohmann::json out_of_range).
  c.push_back(Refused("config_json_r_1e999", phantom, StatusCode::kInvalidArgument,
                      {"'r'", "1e999", "beyond the range"}, [](v1::CreateJobRequest& r) {
                        r.mutable_parameters()->set_config_json(R"({"r": 1e999})");
                      }));
  c.push_back(Refused("request_id_with_a_control_character", phantom, StatusCode::kInvalidArgument,
                      {"request_id"}, [](v1::CreateJobRequest& r) { r.set_request_id("a\nb"); }));
  c.push_back(Refused("digest_not_stored", phantom, StatusCode::kFailedPrecondition,
                      {"upload it first"}, [](v1::CreateJobRequest& r) {
                        r.mutable_input()->mutable_volume_digest()->set_hash(std::string(64, 'a'));
                      }));
  c.push_back(Refused("digest_malformed", phantom, StatusCode::kInvalidArgument, {"XYZ"},
                      [](v1::CreateJobRequest& r) {
                        r.mutable_input()->mutable_volume_digest()->set_hash("XYZ");
                      }));
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

// Two files the VDB fuzzer made: 2 KB and 4 KB whose headers make OpenVDB allocate tens
// of GiB (a string of a declared length, node buffers). InspectVolume opens them in a child
// under the job memory limit; in the server's own process they would take it down.
TEST_F(HardeningTest, InspectingAVdbThatClaimsGigabytesFailsInItsChildNotTheServer) {
  options_.job_limits.memory_bytes = uint64_t{1} << 30;
  StartServer();
  for (const char* name : {"openvdb_claims_gigabytes", "openvdb_gigabyte_name"}) {
    SCOPED_TRACE(name);
    const std::string path = options_.allowed_roots[0] + "/" + name + ".vdb";
    std::filesystem::copy_file(std::string(SHEETMESH_FUZZ_CORPUS) + "/vdb_file/" + name, path);
    v1::InspectVolumeRequest r;
    r.set_path(path);
    v1::InspectVolumeResponse response;
    const grpc::Status st =
        client_->volumes()->InspectVolume(client_->Context().get(), r, &response);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << st.error_message();
    EXPECT_THAT(st.error_message(), HasSubstr(path));
    EXPECT_THAT(st.error_message(), HasSubstr("not a readable .vdb"));
    EXPECT_LT(st.error_message().size(), 1000u);  // not the gigabyte name quoted back
    ExpectServing();
  }
  // A good volume is still inspected, in its own child.
  const std::string good = WritePhantom(options_.allowed_roots[0], "fine", 24, 2);
  v1::InspectVolumeRequest r;
  r.set_path(good);
  v1::InspectVolumeResponse response;
  ASSERT_TRUE(client_->volumes()->InspectVolume(client_->Context().get(), r, &response).ok());
  EXPECT_THAT(response.dims(), ::testing::ElementsAre(24, 24, 24));
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
