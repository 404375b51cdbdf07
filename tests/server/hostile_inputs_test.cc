// The audit's second round through the real gRPC stack: files that name other files (HDF5
// external storage, virtual datasets, external links pointing at /proc/self/environ,
// /etc/passwd, the job store, the scratch of other jobs), small files that claim gigabytes,
// and parameters that ran away. Each ends with its code and a message naming it, within a
// 1 GiB job (a bomb past it would fail RESOURCE_EXHAUSTED instead), without the server's
// secrets in any message, with jobs isolated in children and with them run in-process.
#include <gmock/gmock.h>
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <functional>

#include "absl/strings/str_cat.h"
#include "tests/server/service_fixture.h"
#include "tests/testing/hostile_files.h"

namespace sheetmesh::testing {
namespace {

using ::testing::HasSubstr;

constexpr char kSecret[] = "pg-password-of-the-server-7f3a";

struct Hostile {
  std::string name;
  // Writes the input under `dir` and returns the path to send (a file, folder or file:/ds).
  std::function<std::string(const std::string& dir, const std::string& data_dir)> make;
  bool by_reference = false;
  absl::StatusCode code;
  std::vector<std::string> words;
};

std::vector<Hostile> Cases() {
  using absl::StatusCode;
  using D = const std::string&;
  return {
      {"environ_by_external_storage",
       [](D d, D) { return Hdf5WithExternalStorage(d + "/environ.h5", "/proc/self/environ", 0); },
       false,
       StatusCode::kPermissionDenied,
       {"external storage", "/proc/self/environ"}},
      {"job_store_by_external_storage",
       [](D d, D data) { return Hdf5WithExternalStorage(d + "/db.h5", data + "/jobs.db", 100); },
       false,
       StatusCode::kPermissionDenied,
       {"jobs.db"}},
      {"passwd_by_external_storage_referenced",
       [](D d, D) { return Hdf5WithExternalStorage(d + "/passwd.h5", "/etc/passwd", 0); },
       true,
       StatusCode::kPermissionDenied,
       {"outside the allowed roots", "/etc/passwd"}},
      {"another_jobs_scratch_by_virtual_dataset_referenced",
       [](D d, D data) {
         std::filesystem::create_directories(data + "/scratch/other");
         const std::string other = Hdf5Plain(data + "/scratch/other/volume.h5", "/data");
         return Hdf5Virtual(d + "/vds.h5", other, "/data");
       },
       true,
       StatusCode::kPermissionDenied,
       {"virtual dataset", "outside the allowed roots"}},
      {"missing_outside_file_by_virtual_dataset_referenced",
       [](D d, D data) { return Hdf5Virtual(d + "/gone.h5", data + "/no/such.h5", "/data"); },
       true,
       StatusCode::kPermissionDenied,
       {"outside the allowed roots"}},
      {"outside_file_by_external_link_referenced",
       [](D d, D data) {
         const std::string outside = Hdf5Plain(data + "/../outside.h5", "/secret");
         return Hdf5ExternalLink(d + "/link.h5", outside, "/secret") + ":/data";
       },
       true,
       StatusCode::kPermissionDenied,
       {"external link"}},
      {"hdf5_gigabyte_chunk",
       [](D d, D) { return Hdf5HugeChunk(d + "/chunk.h5", 512); },
       false,
       StatusCode::kInvalidArgument,
       {"512x512x512"}},
      {"hdf5_2000_nested_groups",
       [](D d, D) { return Hdf5NestedGroups(d + "/nested.h5", 2000); },
       false,
       StatusCode::kInvalidArgument,
       {"dataset"}},
      {"npy_40kb_shape",
       [](D d, D) { return NpyWithLongShape(d + "/long.npy", 20000); },
       false,
       StatusCode::kInvalidArgument,
       {"shape"}},
      {"vdb_cut_to_200_bytes",
       [](D d, D) { return VdbCutTo(d + "/cut.vdb", 200); },
       false,
       StatusCode::kInvalidArgument,
       {"not a readable .vdb"}},
      {"jpeg_claiming_65500",
       [](D d, D) { return JpegClaiming(d + "/jpegs", 65500, 65500); },
       true,
       StatusCode::kInvalidArgument,
       {"65500x65500"}},
      {"png_claiming_65500",
       [](D d, D) { return PngClaiming(d + "/pngs", 65500, 65500); },
       true,
       StatusCode::kInvalidArgument,
       {"65500x65500"}},
  };
}

class HostileInputsTest : public ServiceTest, public ::testing::WithParamInterface<bool> {
 protected:
  void SetUp() override {
    ServiceTest::SetUp();
    ::setenv("PGPASSWORD", kSecret, 1);
    options_.isolate_jobs = GetParam();
    options_.job_limits.memory_bytes = uint64_t{1} << 30;
  }
  void TearDown() override {
    ServiceTest::TearDown();
    ::unsetenv("PGPASSWORD");
  }

  // Sends `path` (uploaded, or named under the allowed root) and waits for the end.
  absl::StatusOr<v1::Job> Run(const std::string& id, const std::string& path, bool by_reference,
                              const std::function<void(v1::CreateJobRequest&)>& edit = {}) {
    v1::CreateJobRequest r;
    r.set_request_id(id);
    if (by_reference) {
      r.mutable_input()->set_volume_path(path);
    } else {
      auto digest = client_->Upload(path);
      if (!digest.ok()) return digest.status();
      *r.mutable_input()->mutable_volume_digest() = *digest;
      r.mutable_input()->set_file_name(std::filesystem::path(path).filename().string());
    }
    if (edit) edit(r);
    auto job = client_->CreateJob(r);
    if (!job.ok()) return job.status();
    return WaitFinished(job->name());
  }
};

TEST_P(HostileInputsTest, EachEndsWithItsCodeNamingItAndLeaksNothing) {
  StartServer();
  int n = 0;
  for (const Hostile& c : Cases()) {
    SCOPED_TRACE(c.name);
    const std::string dir = c.by_reference ? absl::StrCat(options_.allowed_roots[0], "/case", ++n)
                                           : dir_.File(absl::StrCat("case", ++n, "/in"));
    std::filesystem::create_directories(dir);
    const std::string path = c.make(dir, options_.data_dir);
    auto done = Run(c.name, path, c.by_reference);
    ASSERT_TRUE(done.ok()) << done.status();
    EXPECT_EQ(done->state(), v1::FAILED);
    EXPECT_EQ(done->error().code(), static_cast<int>(c.code)) << done->error().message();
    for (const std::string& w : c.words) EXPECT_THAT(done->error().message(), HasSubstr(w));
    EXPECT_THAT(done->error().message(), ::testing::Not(HasSubstr(kSecret)));
    EXPECT_EQ(done->attempts(), 1);
    EXPECT_EQ(*client_->Health(), "SERVING");
  }
}

TEST_P(HostileInputsTest, InspectVolumeRefusesWhatAJobRefuses) {
  StartServer();
  const std::string dir = options_.allowed_roots[0] + "/inspect";
  std::filesystem::create_directories(dir);
  for (const std::string& path :
       {Hdf5WithExternalStorage(dir + "/passwd.h5", "/etc/passwd", 0),
        Hdf5WithExternalStorage(dir + "/environ.h5", "/proc/self/environ", 0)}) {
    SCOPED_TRACE(path);
    v1::InspectVolumeRequest r;
    r.set_path(path);
    v1::InspectVolumeResponse response;
    const grpc::Status st =
        client_->volumes()->InspectVolume(client_->Context().get(), r, &response);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::PERMISSION_DENIED) << st.error_message();
    EXPECT_THAT(st.error_message(), HasSubstr("outside the allowed roots"));
  }
}

TEST_P(HostileInputsTest, RunawayParametersAreRefusedOrFinish) {
  StartServer();
  const std::string sample = WritePhantom(options_.allowed_roots[0], "p", 48, 3);
  // Out of the ranges the stages can honour: refused at once, naming the parameter.
  for (const auto& [name, edit] :
       std::vector<std::pair<std::string, std::function<void(v1::CreateJobRequest&)>>>{
           {"tet_min_dihedral",
            [](v1::CreateJobRequest& r) {
              r.mutable_parameters()->set_volume_mesh(true);
              r.mutable_parameters()->set_tet_min_dihedral(69.99);
            }},
           {"surface_seed", [](v1::CreateJobRequest& r) {
              r.mutable_parameters()->set_surface_seed(uint64_t{9007199254740993});
            }}}) {
    auto st = Run("refused-" + name, sample, true, edit);
    EXPECT_EQ(st.status().code(), absl::StatusCode::kInvalidArgument) << name;
    EXPECT_THAT(st.status().message(), HasSubstr(name));
  }
  // Within them, what ran away before finishes now.
  for (const auto& [name, edit] :
       std::vector<std::pair<std::string, std::function<void(v1::CreateJobRequest&)>>>{
           {"detect_t_100",
            [](v1::CreateJobRequest& r) {
              r.mutable_parameters()->set_extract(true);
              r.mutable_parameters()->set_detect_t(100);
            }},
           {"detect_R_1000",
            [](v1::CreateJobRequest& r) {
              r.mutable_parameters()->set_extract(true);
              r.mutable_parameters()->set_detect_r(1000);
            }},
           {"spacing_1e-6", [](v1::CreateJobRequest& r) {
              for (int k = 0; k < 3; ++k) r.mutable_input()->mutable_format()->add_spacing(1e-6);
            }}}) {
    auto done = Run("finishes-" + name, sample, true, edit);
    ASSERT_TRUE(done.ok()) << name << ": " << done.status();
    EXPECT_EQ(done->state(), v1::SUCCEEDED) << name << ": " << done->error().message();
  }
}

// A 4 KB file the HDF5 fuzzer found on which libhdf5 1.10 loops for ever inside H5Ovisit
// (a symbol table that leads back to itself): kept apart from the corpus the test suite
// replays in its own process. A job's child must open its volume within job_limits.open.
TEST_F(ServiceTest, AVolumeWhoseHeaderNeverOpensFailsTheJobInItsChild) {
  options_.job_limits.open = absl::Seconds(3);
  StartServer();
  const std::string path = dir_.File("loop.h5");
  std::filesystem::copy_file(
      std::string(SHEETMESH_FUZZ_CORPUS) + "/../crashers/hdf5_file/hdf5_symbol_table_loop", path);
  auto digest = client_->Upload(path);
  ASSERT_TRUE(digest.ok()) << digest.status();
  auto job = client_->CreateJob(UploadRequest(*digest, "loop.h5", "loop"));
  ASSERT_TRUE(job.ok()) << job.status();
  const v1::Job done = WaitFinished(job->name());
  EXPECT_EQ(done.state(), v1::FAILED);
  EXPECT_EQ(done.error().code(), static_cast<int>(absl::StatusCode::kInvalidArgument))
      << done.error().message();
  EXPECT_THAT(done.error().message(), HasSubstr("did not open within 3 s"));
  EXPECT_EQ(*client_->Health(), "SERVING");
}

// A file on which libhdf5 1.10 itself segfaults (found by the fuzzer; kept with the library's
// other crashers, apart from the corpus the test suite replays in its own process): the
// job's child dies, the job fails naming the signal and the reading, the server serves on.
TEST_F(ServiceTest, AReaderLibraryCrashingOnAFileFailsOnlyThatJob) {
  StartServer();
  const std::string path = dir_.File("segv.h5");
  std::filesystem::copy_file(
      std::string(SHEETMESH_FUZZ_CORPUS) + "/../crashers/hdf5_file/hdf5_local_heap_segv", path);
  auto digest = client_->Upload(path);
  ASSERT_TRUE(digest.ok()) << digest.status();
  auto job = client_->CreateJob(UploadRequest(*digest, "segv.h5", "segv"));
  ASSERT_TRUE(job.ok()) << job.status();
  const v1::Job done = WaitFinished(job->name());
  EXPECT_EQ(done.state(), v1::FAILED);
  EXPECT_EQ(done.error().code(), static_cast<int>(absl::StatusCode::kInternal));
  EXPECT_THAT(done.error().message(), HasSubstr("SIGSEGV"));
  EXPECT_THAT(done.error().message(), HasSubstr("while reading the volume"));
  EXPECT_EQ(done.attempts(), 1);
  EXPECT_EQ(*client_->Health(), "SERVING");
}

INSTANTIATE_TEST_SUITE_P(IsolatedAndInProcess, HostileInputsTest, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& i) {
                           return i.param ? "Isolated" : "InProcess";
                         });

}  // namespace
}  // namespace sheetmesh::testing
