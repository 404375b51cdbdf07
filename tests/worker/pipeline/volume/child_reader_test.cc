// Child readers: a volume read by the CLI's `_serve-volume` child is the volume read here,
// its reader's errors come back as they are, and a library that crashes or loops on a damaged
// file costs the child, not this process.
#include "worker/pipeline/volume/child_reader.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "tests/testing/bad_volumes.h"
#include "tests/testing/status_matchers.h"
#include "tests/testing/temp_dir.h"
#include "worker/pipeline/volume/volume_open.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::IsOk;
using ::sheetmesh::testing::StatusIs;
using ::sheetmesh::testing::TempDir;
using ::testing::AllOf;
using ::testing::HasSubstr;

OpenOptions InChild(double open_seconds = 30) {
  OpenOptions o;
  o.child_reader.program = SHEETMESH_PIPELINE_BINARY;
  o.child_reader.open_seconds = open_seconds;
  return o;
}

std::string Crasher(const std::string& name) {
  return std::string(SHEETMESH_FUZZ_CRASHERS) + "/hdf5_file/" + name;
}

TEST(ChildReaderTest, TheFormatsALibraryParsesAreReadByTheChild) {
  for (const char* f : {"vdb", "hdf5", "dicom", "png", "jpeg", "tiff", "folder"}) {
    EXPECT_TRUE(ReadByLibrary(f)) << f;
  }
  for (const char* f : {"raw", "nrrd", "npy", "mrc", "nifti"}) EXPECT_FALSE(ReadByLibrary(f)) << f;
}

TEST(ChildReaderTest, AVolumeReadInAChildIsTheVolumeReadHere) {
  TempDir tmp;
  const DenseVolume v = testing::SheetVolume({37, 29, 23});
  for (const char* name : {"s.vdb", "s.tif"}) {
    const std::string path = tmp.File(name);
    ASSERT_THAT(testing::WriteVolume(path, v), IsOk());
    absl::StatusOr<std::unique_ptr<VolumeSource>> here = OpenVolume(path);
    absl::StatusOr<std::unique_ptr<VolumeSource>> child = OpenVolume(path, InChild());
    ASSERT_THAT(here.status(), IsOk());
    ASSERT_THAT(child.status(), IsOk());
    EXPECT_EQ((*child)->info().dims, (*here)->info().dims);
    EXPECT_EQ((*child)->info().format, (*here)->info().format);
    absl::StatusOr<DenseVolume> a = ReadDense(**here), b = ReadDense(**child);
    ASSERT_THAT(b.status(), IsOk());
    EXPECT_EQ(a->data, b->data) << name;
    // Slabs in any order, as passes ask them.
    std::vector<std::byte> slab(static_cast<size_t>(37 * 29 * 5));
    ASSERT_THAT((*child)->ReadSlices(17, 5, slab), IsOk());
    EXPECT_TRUE(std::equal(slab.begin(), slab.end(), a->data.begin() + 37 * 29 * 17));
    EXPECT_THAT((*child)->ReadSlices(20, 5, slab), StatusIs(absl::StatusCode::kInvalidArgument));
  }
}

TEST(ChildReaderTest, TheReadersErrorsComeBackAsTheyAre) {
  TempDir tmp;
  EXPECT_THAT(OpenVolume(tmp.File("missing.vdb"), InChild()).status(),
              StatusIs(absl::StatusCode::kNotFound, HasSubstr("missing.vdb")));
  const std::string cut = tmp.File("cut.vdb");
  ASSERT_THAT(testing::WriteVolume(cut, testing::SheetVolume({40, 30, 20})), IsOk());
  testing::CutFile(cut, 0.5);
  EXPECT_THAT(OpenVolume(cut, InChild()).status(),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("cut.vdb")));
}

TEST(ChildReaderTest, ALibraryThatCrashesCostsTheChildOnly) {
  // libhdf5 1.10.8 reads out of its buffers on this file (SIGSEGV in this process before).
  const std::string file = Crasher("hdf5_local_heap_segv");
  ASSERT_TRUE(std::filesystem::exists(file)) << file;
  TempDir tmp;
  const std::string path = tmp.File("damaged.h5");
  std::filesystem::copy_file(file, path);
  EXPECT_THAT(OpenVolume(path, InChild()).status(),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       AllOf(HasSubstr(path), HasSubstr("libhdf5"), HasSubstr("killed by"))));
}

TEST(ChildReaderTest, ALibraryThatLoopsIsStoppedAtItsDeadline) {
  const std::string file = Crasher("hdf5_symbol_table_loop");  // libhdf5 loops for ever
  ASSERT_TRUE(std::filesystem::exists(file)) << file;
  TempDir tmp;
  const std::string path = tmp.File("loop.h5");
  std::filesystem::copy_file(file, path);
  EXPECT_THAT(OpenVolume(path, InChild(/*open_seconds=*/2)).status(),
              StatusIs(absl::StatusCode::kDeadlineExceeded,
                       AllOf(HasSubstr(path), HasSubstr("did not answer in time"))));
}

}  // namespace
}  // namespace sheetmesh
