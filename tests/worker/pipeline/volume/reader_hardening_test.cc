// The readers against the audit's bad files: every size a header declares is checked before
// anything is allocated, everything a header promises is verified, a file that shrinks while
// it is read is an error (not a signal), a header may name no file outside the allowed roots,
// and no third-party exception leaves a reader. Each case names the file and the value.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "absl/strings/match.h"
#include "common/file_util.h"
#include "tests/testing/bad_volumes.h"
#include "tests/testing/shared_data.h"
#include "tests/testing/status_matchers.h"
#include "tests/testing/temp_dir.h"
#include "worker/pipeline/volume/nrrd_io.h"
#include "worker/pipeline/volume/raw_io.h"
#include "worker/pipeline/volume/tiff_io.h"
#include "worker/pipeline/volume/vdb_io.h"
#include "worker/pipeline/volume/volume_open.h"
#include "worker/pipeline/voxel/phase_selection.h"
#include "worker/pipeline/voxel/sheet_input.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::IsOk;
using ::sheetmesh::testing::StatusIs;
using ::sheetmesh::testing::TempDir;
using ::testing::AllOf;
using ::testing::AnyOf;
using ::testing::HasSubstr;

// Opens and reads every slice: the first error, or OK.
absl::Status OpenAndReadAll(const std::string& path, const OpenOptions& options = {}) {
  auto source = OpenVolume(path, options);
  if (!source.ok()) return source.status();
  const VolumeInfo& info = (*source)->info();
  std::vector<std::byte> slice(static_cast<size_t>(info.dims.nx * info.dims.ny) *
                               BytesPerVoxel(info.dtype));
  for (int64_t z = 0; z < info.dims.nz; ++z) {
    if (absl::Status st = (*source)->ReadSlices(z, 1, slice); !st.ok()) return st;
  }
  return absl::OkStatus();
}

TEST(ReaderHardeningTest, TiffHeaderBombsAreRefusedBeforeAllocating) {
  TempDir tmp;
  for (uint32_t side : {60000u, 200000u}) {
    for (bool deflate : {false, true}) {
      const std::string path = tmp.File(absl::StrCat("bomb_", side, deflate ? "_z" : "", ".tif"));
      ASSERT_THAT(WriteFileAtomically(path, testing::TiffClaiming(side, side, deflate)), IsOk());
      ASSERT_LT(std::filesystem::file_size(path), 20000u);
      const absl::Status st = OpenAndReadAll(path);
      EXPECT_THAT(st.code(),
                  AnyOf(absl::StatusCode::kInvalidArgument, absl::StatusCode::kResourceExhausted))
          << "side " << side << (deflate ? " deflate" : "") << ": " << st;
      EXPECT_THAT(std::string(st.message()), AllOf(HasSubstr(path), HasSubstr(absl::StrCat(side))));
    }
  }
}

TEST(ReaderHardeningTest, ACutMultiPageTiffNamesTheFirstMissingPage) {
  TempDir tmp;
  const std::string path = tmp.File("stack.tif");
  ASSERT_THAT(testing::WriteVolume(path, testing::SheetVolume({40, 30, 20})), IsOk());
  ASSERT_THAT(OpenAndReadAll(path), IsOk());
  testing::CutFile(path, 0.5);
  EXPECT_THAT(OpenAndReadAll(path), StatusIs(absl::StatusCode::kInvalidArgument,
                                             AllOf(HasSubstr(path), HasSubstr("page"))));
}

TEST(ReaderHardeningTest, TheCutNetlTiffIsRefusedNotReadAsOnePage) {
  SM_REQUIRE_SHARED_DATA("netl_binary_fracture_small.tif");
  const std::string netl = testing::SharedDataFile("netl_binary_fracture_small.tif");
  TempDir tmp;
  const std::string path = tmp.File("netl_cut.tif");
  std::filesystem::copy_file(netl, path);
  std::filesystem::resize_file(path, 400000);  // the audit's `head -c 400000`
  EXPECT_THAT(OpenAndReadAll(path), StatusIs(absl::StatusCode::kInvalidArgument,
                                             AllOf(HasSubstr(path), HasSubstr("page"))));
}

TEST(ReaderHardeningTest, ACutVdbIsInvalidArgumentNotAnException) {
  TempDir tmp;
  const std::string whole = tmp.File("whole.vdb");
  ASSERT_THAT(testing::WriteVolume(whole, testing::SheetVolume({48, 40, 32})), IsOk());
  ASSERT_THAT(OpenAndReadAll(whole), IsOk());
  for (double keep : {0.05, 0.3, 0.6, 0.95}) {
    const std::string path = tmp.File(absl::StrCat("cut_", keep, ".vdb"));
    std::filesystem::copy_file(whole, path);
    testing::CutFile(path, keep);
    EXPECT_THAT(OpenAndReadAll(path), StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr(path)))
        << "kept " << keep;
  }
}

TEST(ReaderHardeningTest, AFileThatShrinksWhileReadIsAnErrorNotASignal) {
  TempDir tmp;
  for (const char* name : {"v_64x64x64_u8.raw", "v.tif", "v.nrrd"}) {
    const std::string path = tmp.File(name);
    const DenseVolume v = testing::SheetVolume({64, 64, 64});
    if (absl::EndsWith(name, ".nrrd")) {
      auto sink = CreateNrrdWriter(path, v.info);
      ASSERT_THAT(sink, IsOk());
      ASSERT_THAT(WriteDense(v, **sink), IsOk());
    } else {
      ASSERT_THAT(testing::WriteVolume(path, v), IsOk());
    }
    auto source = OpenVolume(path);
    ASSERT_THAT(source, IsOk()) << name;
    std::filesystem::resize_file(path, std::filesystem::file_size(path) / 3);
    std::vector<std::byte> slice(64 * 64);
    absl::Status st = absl::OkStatus();
    for (int64_t z = 0; z < 64 && st.ok(); ++z) st = (*source)->ReadSlices(z, 1, slice);
    EXPECT_THAT(st, StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr(path))) << name;
  }
}

TEST(ReaderHardeningTest, ANrrdHeaderMayNameNoFileOutsideTheAllowedRoots) {
  TempDir tmp;
  std::filesystem::create_directories(tmp.File("root"));
  const std::string header = tmp.File("root/x.nhdr");
  ASSERT_THAT(WriteFileAtomically(header, testing::HeaderNaming("/etc/passwd")), IsOk());
  // A symbolic link under the root that leads out of it is outside too.
  std::filesystem::create_symlink("/etc/passwd", tmp.File("root/link.raw"));
  const std::string linked = tmp.File("root/y.nhdr");
  ASSERT_THAT(WriteFileAtomically(linked, testing::HeaderNaming("link.raw")), IsOk());
  OpenOptions confined;
  confined.limits.confine_named_files = true;
  confined.limits.named_file_roots = {tmp.File("root")};
  for (const std::string& path : {header, linked}) {
    EXPECT_THAT(OpenAndReadAll(path, confined),
                StatusIs(absl::StatusCode::kPermissionDenied, HasSubstr(path)));
  }
  // An upload may name no file at all.
  OpenOptions upload;
  upload.limits.confine_named_files = true;
  EXPECT_THAT(OpenAndReadAll(header, upload), StatusIs(absl::StatusCode::kPermissionDenied));
  // Its own data file beside it, under the root, reads.
  const DenseVolume v = testing::SheetVolume({8, 8, 8});
  ASSERT_THAT(testing::WriteVolume(tmp.File("root/d.raw"), v), IsOk());
  ASSERT_THAT(WriteFileAtomically(tmp.File("root/z.nhdr"),
                                  "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 8 8 8\n"
                                  "encoding: raw\ndata file: d.raw\n\n"),
              IsOk());
  EXPECT_THAT(OpenAndReadAll(tmp.File("root/z.nhdr"), confined), IsOk());
}

TEST(ReaderHardeningTest, HeaderSizesAreCheckedAgainstTheFileAndTheBudget) {
  TempDir tmp;
  const std::string path = tmp.File("huge.nrrd");
  ASSERT_THAT(WriteFileAtomically(path,
                                  "NRRD0004\ntype: float\ndimension: 3\nsizes: 100000 100000 "
                                  "100000\nencoding: raw\n\nxxxx"),
              IsOk());
  const absl::Status huge = OpenAndReadAll(path);
  EXPECT_THAT(huge.code(),
              AnyOf(absl::StatusCode::kInvalidArgument, absl::StatusCode::kResourceExhausted));
  EXPECT_THAT(std::string(huge.message()), HasSubstr("100000"));
  // One slice larger than the memory budget is refused at open, naming both sizes.
  const std::string raw = tmp.File("wide_4096x4096x2_u8.raw");
  std::ofstream(raw).close();
  std::filesystem::resize_file(raw, 4096 * 4096 * 2);
  OpenOptions small;
  small.limits.memory_bytes = 1 << 20;
  EXPECT_THAT(OpenVolume(raw, small),
              StatusIs(absl::StatusCode::kResourceExhausted, HasSubstr("16777216")));
}

TEST(ReaderHardeningTest, NanIsNeverSheet) {
  TempDir tmp;
  const std::string path = testing::WriteNanVolume(tmp.path(), 16);
  SM_ASSERT_OK_AND_ASSIGN(auto source, OpenVolume(path));
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet all, SelectPhase(*source, PhaseSelection::NonZero()));
  EXPECT_EQ(all.size(), 16u * 16u);  // the plane of 1.0 alone
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet window,
                          SelectPhase(*source, PhaseSelection::Window(-1e30, 1e30)));
  EXPECT_EQ(window.size(), 16u * 16u);
}

TEST(ReaderHardeningTest, AGrayscaleFloatVolumeNeedsItsSheetPhaseGiven) {
  TempDir tmp;
  SheetInput in;
  in.path = testing::WriteGrayscale(tmp.path(), 24);
  EXPECT_THAT(LoadSheetPhase(in), StatusIs(absl::StatusCode::kInvalidArgument,
                                           AllOf(HasSubstr(in.path), HasSubstr("input.window"))));
  in.selection = PhaseSelection::Window(0, 5);  // the dark sheet
  SM_ASSERT_OK_AND_ASSIGN(SheetPhase phase, LoadSheetPhase(in));
  EXPECT_EQ(phase.sheet.size(), 24u * 24u);
}

}  // namespace
}  // namespace sheetmesh
