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
#include "tests/testing/hostile_files.h"
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

// Options of a volume sent to the server (it may name no other file), of one referenced under
// `root` (it may name files under the root), and of a local user's own file (anything).
OpenOptions Uploaded() {
  OpenOptions o;
  o.limits.confine_named_files = true;
  return o;
}
OpenOptions Referenced(const std::string& root) {
  OpenOptions o = Uploaded();
  o.limits.named_file_roots = {root};
  return o;
}

TEST(ReaderHardeningTest, AnHdf5DatasetStoredInAnotherFileIsRefusedUnlessThatFileIsAllowed) {
  TempDir tmp;
  const std::string root = tmp.File("root");
  std::filesystem::create_directories(root);
  for (const std::string secret : {"/proc/self/environ", "/etc/passwd"}) {
    const std::string path = testing::Hdf5WithExternalStorage(tmp.File("root/leak.h5"), secret,
                                                              secret == "/etc/passwd" ? 3 : 0);
    EXPECT_THAT(OpenAndReadAll(path + ":/data", Uploaded()),
                StatusIs(absl::StatusCode::kPermissionDenied,
                         AllOf(HasSubstr(path), HasSubstr("external storage"), HasSubstr(secret))));
    EXPECT_THAT(OpenAndReadAll(path + ":/data", Referenced(root)),
                StatusIs(absl::StatusCode::kPermissionDenied,
                         AllOf(HasSubstr("outside the allowed roots"), HasSubstr(secret))));
  }
  // A raw file beside it, under the root, may hold its voxels; so may any file offline.
  ASSERT_THAT(WriteFileAtomically(tmp.File("root/voxels.bin"), std::string(4, '\x07')), IsOk());
  const std::string beside =
      testing::Hdf5WithExternalStorage(tmp.File("root/beside.h5"), "voxels.bin", 2);
  EXPECT_THAT(OpenAndReadAll(beside + ":/data", Referenced(root)), IsOk());
  EXPECT_THAT(OpenAndReadAll(beside + ":/data", Uploaded()),
              StatusIs(absl::StatusCode::kPermissionDenied, HasSubstr("voxels.bin")));
  EXPECT_THAT(OpenAndReadAll(beside + ":/data"), IsOk());
}

TEST(ReaderHardeningTest, Hdf5VirtualDatasetsAndExternalLinksReachOnlyAllowedFiles) {
  TempDir tmp;
  const std::string root = tmp.File("root");
  std::filesystem::create_directories(root);
  const std::string outside = testing::Hdf5Plain(tmp.File("outside.h5"), "/secret");
  const std::string inside = testing::Hdf5Plain(tmp.File("root/inside.h5"), "/scan");
  struct Case {
    std::string path;
    bool allowed_under_root;
  };
  const std::vector<Case> cases = {
      {testing::Hdf5Virtual(tmp.File("root/vds_out.h5"), outside, "/secret"), false},
      {testing::Hdf5Virtual(tmp.File("root/vds_in.h5"), "inside.h5", "/scan"), true},
      {testing::Hdf5ExternalLink(tmp.File("root/link_out.h5"), outside, "/secret"), false},
      {testing::Hdf5ExternalLink(tmp.File("root/link_in.h5"), inside, "/scan"), true},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.path);
    const std::string volume = c.path + ":/data";
    EXPECT_THAT(OpenAndReadAll(volume, Uploaded()),
                StatusIs(absl::StatusCode::kPermissionDenied, HasSubstr(c.path)));
    if (c.allowed_under_root) {
      EXPECT_THAT(OpenAndReadAll(volume, Referenced(root)), IsOk());
    } else {
      EXPECT_THAT(OpenAndReadAll(volume, Referenced(root)),
                  StatusIs(absl::StatusCode::kPermissionDenied, HasSubstr("outside.h5")));
    }
    EXPECT_THAT(OpenAndReadAll(volume), IsOk()) << "a local user's own file reads";
  }
}

TEST(ReaderHardeningTest, Hdf5ChunkNestingAndEmptinessBombsEndInAnErrorNamingThem) {
  TempDir tmp;
  // One 512^3 chunk (128 MiB decoded) for a 48^3 dataset.
  const std::string chunked = testing::Hdf5HugeChunk(tmp.File("chunk.h5"), 512);
  EXPECT_THAT(OpenAndReadAll(chunked + ":/data"),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       AllOf(HasSubstr(chunked), HasSubstr("512x512x512"))));
  // A chunk a little wider than its dataset reads.
  const std::string fine = testing::Hdf5HugeChunk(tmp.File("fine.h5"), 64);
  EXPECT_THAT(OpenAndReadAll(fine + ":/data"), IsOk());
  // Declared, never written: no data behind the dims.
  const std::string empty = testing::Hdf5NeverWritten(tmp.File("empty.h5"), 256);
  EXPECT_THAT(OpenAndReadAll(empty + ":/data"),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       AllOf(HasSubstr(empty), HasSubstr("16777216 bytes"))));
  // 2,000 nested groups: listing them stops at its bound; named, the dataset opens.
  const std::string nested = testing::Hdf5NestedGroups(tmp.File("nested.h5"), 2000);
  EXPECT_THAT(OpenAndReadAll(nested), StatusIs(absl::StatusCode::kInvalidArgument,
                                               AllOf(HasSubstr(nested), HasSubstr("dataset"))));
  std::string deep;
  for (int i = 0; i < 2000; ++i) deep += "/g";
  EXPECT_THAT(OpenAndReadAll(nested + ":" + deep + "/data"), IsOk());
}

TEST(ReaderHardeningTest, ANpyShapeOf20000ExtentsIsInvalidArgumentNotACrash) {
  TempDir tmp;
  const std::string path = testing::NpyWithLongShape(tmp.File("long.npy"), 20000);
  ASSERT_GT(std::filesystem::file_size(path), 40000u);
  EXPECT_THAT(OpenAndReadAll(path),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       AllOf(HasSubstr(path), HasSubstr("shape"), HasSubstr("not 2D or 3D"))));
}

TEST(ReaderHardeningTest, SlicesClaimingMoreThanTheirBytesCanHoldAreRefusedBeforeDecoding) {
  TempDir tmp;
  for (const std::string& folder : {testing::JpegClaiming(tmp.File("jpeg"), 65500, 65500),
                                    testing::PngClaiming(tmp.File("png"), 65500, 65500)}) {
    EXPECT_THAT(OpenAndReadAll(folder),
                StatusIs(absl::StatusCode::kInvalidArgument,
                         AllOf(HasSubstr(folder), HasSubstr("65500x65500"), HasSubstr(":1"))));
  }
}

TEST(ReaderHardeningTest, AVdbCutAnywhereInItsHeaderIsInvalidArgument) {
  TempDir tmp;
  const std::string path = tmp.File("cut.vdb");
  ASSERT_THAT(testing::WriteVolume(path, testing::SheetVolume({48, 40, 32})), IsOk());
  const int64_t size = static_cast<int64_t>(std::filesystem::file_size(path));
  // Every cut in the first 600 bytes (the header and the first descriptor: the audit cut at
  // 200), then every 5% of the file.
  for (int64_t keep = 0; keep < size; keep += keep < 600 ? 1 : size / 20) {
    ASSERT_THAT(testing::VdbCutTo(path, keep), HasSubstr("cut.vdb"));
    EXPECT_THAT(OpenAndReadAll(path), StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr(path)))
        << "kept " << keep << " of " << size << " bytes";
  }
}

}  // namespace
}  // namespace sheetmesh
