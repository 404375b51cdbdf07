// Volumes of several files through the service: a folder of TIFF slices and a detached
// NRRD uploaded with find-missing (only new slices travel), laid out for the reader, and
// the manifests the server must refuse.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>

#include "nlohmann/json.hpp"
#include "tests/server/service_fixture.h"
#include "tests/testing/status_matchers.h"
#include "worker/pipeline/volume/tiff_io.h"
#include "worker/pipeline/volume/volume_open.h"

namespace sheetmesh::testing {
namespace {

using ::testing::HasSubstr;

class VolumeFilesTest : public ServiceTest {
 protected:
  // The job's report.json, once it has succeeded.
  nlohmann::json Report(const v1::Job& job) {
    EXPECT_EQ(job.state(), v1::SUCCEEDED) << job.error().message();
    for (const v1::Artifact& a : job.artifacts()) {
      if (a.name() != "report.json") continue;
      const std::string path = dir_.File(job.name().substr(5) + ".json");
      EXPECT_TRUE(client_->Download(a.digest(), path).ok());
      return nlohmann::json::parse(Slurp(path));
    }
    ADD_FAILURE() << job.name() << " has no report.json";
    return {};
  }

  v1::Job Run(const v1::VolumeFiles& files, const std::string& file_name, const std::string& id) {
    v1::CreateJobRequest r;
    r.set_request_id(id);
    *r.mutable_input()->mutable_volume_files() = files;
    r.mutable_input()->set_file_name(file_name);
    r.set_no_cache(true);
    auto job = client_->CreateJob(r);
    EXPECT_TRUE(job.ok()) << job.status();
    return job.ok() ? WaitFinished(job->name()) : v1::Job();
  }

  absl::Status Create(const v1::VolumeFiles& files, const std::string& id) {
    v1::CreateJobRequest r;
    r.set_request_id(id);
    *r.mutable_input()->mutable_volume_files() = files;
    return client_->CreateJob(r).status();
  }
};

TEST_F(VolumeFilesTest, AFolderOfSlicesIsOneVolumeAndOnlyChangedSlicesTravel) {
  StartServer();
  const std::string raw = WritePhantom(dir_.path(), "rock", 40, 5);
  SM_ASSERT_OK_AND_ASSIGN(auto source, OpenVolume(raw, {}));
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume v, ReadDense(*source));
  const std::string folder = dir_.File("slices");
  SM_ASSERT_OK_AND_ASSIGN(auto sink, CreateTiffFolderWriter(folder, v.info));
  ASSERT_TRUE(WriteDense(v, *sink).ok());

  SM_ASSERT_OK_AND_ASSIGN(client::VolumeOnDisk local, client::VolumeFilesOf(folder));
  ASSERT_EQ(local.files.size(), 40u);
  EXPECT_EQ(local.main, "");
  SM_ASSERT_OK_AND_ASSIGN(client::VolumeUpload up, client_->UploadVolumeFiles(local.files));
  EXPECT_EQ(up.files_sent, 40);
  const v1::Job by_files = Run(up.files, "slices", "folder-1");
  // The same voxels uploaded as one raw file give the same mesh.
  SM_ASSERT_OK_AND_ASSIGN(v1::Digest d, client_->Upload(raw));
  auto one = client_->CreateJob(UploadRequest(d, std::filesystem::path(raw).filename(), "raw-1"));
  ASSERT_TRUE(one.ok()) << one.status();
  const nlohmann::json a = Report(by_files), b = Report(WaitFinished(one->name()));
  ASSERT_FALSE(a.is_null());
  EXPECT_EQ(a["input"]["format"], "tiff-folder");
  EXPECT_EQ(a["similarity"], b["similarity"]);
  EXPECT_EQ(a["surface"]["triangles"], b["surface"]["triangles"]);

  // One slice changes: only it is sent again.
  DenseVolume w = v;
  for (int64_t y = 0; y < 40; ++y)
    for (int64_t x = 0; x < 40; ++x) w.Set(x, y, 7, 0);
  SM_ASSERT_OK_AND_ASSIGN(auto sink2, CreateTiffFolderWriter(folder, w.info));
  ASSERT_TRUE(WriteDense(w, *sink2).ok());
  SM_ASSERT_OK_AND_ASSIGN(local, client::VolumeFilesOf(folder));
  SM_ASSERT_OK_AND_ASSIGN(client::VolumeUpload again, client_->UploadVolumeFiles(local.files));
  EXPECT_EQ(again.files_sent, 1);
  EXPECT_EQ(again.bytes_sent, again.total_bytes / 40);
  const nlohmann::json c = Report(Run(again.files, "slices", "folder-2"));
  EXPECT_NE(c["similarity"], a["similarity"]);
  // The server kept nothing of the job's layout.
  EXPECT_FALSE(std::filesystem::exists(dir_.File("data/scratch/inputs")) &&
               !std::filesystem::is_empty(dir_.File("data/scratch/inputs")));
}

TEST_F(VolumeFilesTest, ADetachedNrrdTravelsWithItsDataFile) {
  StartServer();
  const std::string raw = WritePhantom(dir_.path(), "rock", 32, 9);
  std::filesystem::create_directories(dir_.File("nrrd/data"));
  std::filesystem::copy_file(raw, dir_.File("nrrd/data/rock.raw"));
  // teem and Slicer end detached headers without a blank line.
  std::ofstream(dir_.File("nrrd/rock.nhdr"))
      << "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 32 32 32\nencoding: raw\n"
         "spacings: 2 2 2\ndata file: ./data/rock.raw\n";
  SM_ASSERT_OK_AND_ASSIGN(client::VolumeOnDisk local,
                          client::VolumeFilesOf(dir_.File("nrrd/rock.nhdr")));
  ASSERT_EQ(local.files.size(), 2u);
  EXPECT_EQ(local.main, "rock.nhdr");
  EXPECT_EQ(local.files[1].name, "data/rock.raw");
  SM_ASSERT_OK_AND_ASSIGN(client::VolumeUpload up, client_->UploadVolumeFiles(local.files));
  up.files.set_main(local.main);
  const nlohmann::json r = Report(Run(up.files, "rock.nhdr", "nhdr-1"));
  ASSERT_FALSE(r.is_null());
  EXPECT_EQ(r["input"]["spacing"], nlohmann::json::array({2.0, 2.0, 2.0}));

  // Without its data file the reader says which file it lacks; nothing of the server's
  // own storage is reachable from the header.
  v1::VolumeFiles header_only;
  *header_only.add_files() = up.files.files(0);
  header_only.set_main("rock.nhdr");
  const v1::Job lacking = Run(header_only, "rock.nhdr", "nhdr-2");
  EXPECT_EQ(lacking.state(), v1::FAILED);
  EXPECT_THAT(lacking.error().message(), HasSubstr("rock.raw"));

  // A header whose data file lies outside its folder cannot be uploaded as one volume.
  std::ofstream(dir_.File("nrrd/far.nhdr"))
      << "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 32 32 32\nencoding: raw\n"
         "data file: ../rock_32x32x32_u8.raw\n";
  EXPECT_THAT(client::VolumeFilesOf(dir_.File("nrrd/far.nhdr")).status(),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       ::testing::AllOf(HasSubstr("far.nhdr"), HasSubstr("data file"),
                                        HasSubstr("../rock_32x32x32_u8.raw"))));
}

TEST_F(VolumeFilesTest, BadManifestsAreRefusedNamingTheEntry) {
  StartServer();
  WriteRandomFile(dir_.File("a.tif"), 100, 1);
  SM_ASSERT_OK_AND_ASSIGN(v1::Digest d, client_->Upload(dir_.File("a.tif")));
  auto manifest = [&](std::vector<std::string> names, const std::string& main = "") {
    v1::VolumeFiles f;
    for (const std::string& n : names) {
      v1::VolumeFiles::File* e = f.add_files();
      e->set_name(n);
      *e->mutable_digest() = d;
    }
    f.set_main(main);
    return f;
  };
  struct Case {
    v1::VolumeFiles files;
    absl::StatusCode code;
    std::string says;
  };
  v1::VolumeFiles unstored = manifest({"a.tif", "b.tif"});
  unstored.mutable_files(1)->mutable_digest()->set_hash(std::string(64, 'b'));
  v1::VolumeFiles bad_digest = manifest({"a.tif"});
  bad_digest.mutable_files(0)->mutable_digest()->set_hash("xyz");
  const std::vector<Case> cases = {
      {manifest({}), absl::StatusCode::kInvalidArgument, "input.volume_files.files is empty"},
      {manifest({"../../etc/passwd"}), absl::StatusCode::kInvalidArgument,
       "input.volume_files.files[0].name '../../etc/passwd'"},
      {manifest({"/abs.tif"}), absl::StatusCode::kInvalidArgument, "files[0].name '/abs.tif'"},
      {manifest({"a.tif", "x//b.tif"}), absl::StatusCode::kInvalidArgument, "files[1].name"},
      {manifest({"a.tif", "a.tif"}), absl::StatusCode::kInvalidArgument, "given twice"},
      {manifest({"a", "a/b.tif"}), absl::StatusCode::kInvalidArgument, "both a file and"},
      {manifest({"a.tif"}, "scan.nhdr"), absl::StatusCode::kInvalidArgument,
       "input.volume_files.main 'scan.nhdr'"},
      {bad_digest, absl::StatusCode::kInvalidArgument, "files[0] ('a.tif').digest"},
      {unstored, absl::StatusCode::kFailedPrecondition, "1 of 2 files are not stored (b.tif)"},
  };
  int k = 0;
  for (const Case& c : cases) {
    EXPECT_THAT(Create(c.files, absl::StrCat("bad-", k++)), StatusIs(c.code, HasSubstr(c.says)))
        << c.says;
  }
}

}  // namespace
}  // namespace sheetmesh::testing
