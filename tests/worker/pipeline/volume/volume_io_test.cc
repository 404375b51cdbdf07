// Round trips and bad input for every volume reader and writer.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <tiffio.h>

#include <filesystem>
#include <fstream>

#include "absl/strings/str_cat.h"
#include "common/file_util.h"
#include "tests/testing/status_matchers.h"
#include "tests/testing/temp_dir.h"
#include "worker/pipeline/volume/nrrd_io.h"
#include "worker/pipeline/volume/raw_io.h"
#include "worker/pipeline/volume/tiff_io.h"
#include "worker/pipeline/volume/vdb_io.h"
#include "worker/pipeline/volume/volume_open.h"
#include "worker/pipeline/voxel/voxel_set_vdb.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::IsOk;
using ::sheetmesh::testing::StatusIs;
using ::sheetmesh::testing::TempDir;
using ::testing::HasSubstr;

// A volume whose every voxel differs from its neighbours, with zeros in between so that
// sparse formats have background to skip.
DenseVolume Pattern(DType dtype, Dims dims = {7, 5, 4}) {
  DenseVolume v = DenseVolume::Zeros(dims, dtype);
  v.info.placement.spacing = {0.5, 0.25, 2.0};
  v.info.placement.origin = {1, -2, 3};
  v.info.placement.unit = "mm";
  for (int z = 0; z < dims.nz; ++z) {
    for (int y = 0; y < dims.ny; ++y) {
      for (int x = 0; x < dims.nx; ++x) {
        double value = (x * 7 + y * 13 + z * 29) % 5 == 0 ? 0 : 1 + x + 10 * y + 50 * z;
        if (dtype == DType::kUInt16) value *= 200;                 // above 255
        if (dtype == DType::kFloat32) value = value * 0.75 - 3.5;  // fractional, negative
        if (dtype == DType::kUInt8) value = std::fmod(value, 256);
        v.Set(x, y, z, value);
      }
    }
  }
  return v;
}

void ExpectSameVoxels(const DenseVolume& a, const DenseVolume& b) {
  ASSERT_EQ(a.info.dims, b.info.dims);
  ASSERT_EQ(a.info.dtype, b.info.dtype);
  EXPECT_TRUE(a.data == b.data) << "voxel data differ";
}

struct FormatCase {
  VolumeFormat format;
  const char* name;
  bool keeps_placement;
};

// Whether a writer left a part file behind in `dir`.
bool HasPartFile(const std::string& dir) {
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir)) {
    if (e.path().extension() == ".part") return true;
  }
  return false;
}

class RoundTripTest : public ::testing::TestWithParam<std::tuple<FormatCase, DType>> {};

TEST_P(RoundTripTest, WriteThenReadGivesIdenticalVoxels) {
  const auto [fc, dtype] = GetParam();
  TempDir tmp;
  const DenseVolume in = Pattern(dtype);
  std::string path = tmp.File(std::string("vol") + fc.name);
  if (fc.format == VolumeFormat::kRaw) {
    path = tmp.File(absl::StrCat("vol_7x5x4_", DTypeName(dtype), ".raw"));
  }
  SM_ASSERT_OK_AND_ASSIGN(auto sink, CreateVolumeWriter(path, in.info, fc.format));
  ASSERT_THAT(WriteDense(in, *sink), IsOk());
  ASSERT_FALSE(HasPartFile(tmp.path()));
  SM_ASSERT_OK_AND_ASSIGN(auto source, OpenVolume(path));
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume out, ReadDense(*source));
  ExpectSameVoxels(in, out);
  if (fc.keeps_placement) {
    const Placement& p = source->info().placement;
    EXPECT_NEAR(p.spacing.x, 0.5, 1e-6);
    EXPECT_NEAR(p.spacing.y, 0.25, 1e-6);
    EXPECT_NEAR(p.spacing.z, 2.0, 1e-6);
  }
  // Reading slices out of order gives the same voxels (readers of streams restart).
  const size_t slice = in.data.size() / 4;
  std::vector<std::byte> last(slice), first(slice);
  ASSERT_THAT(source->ReadSlices(3, 1, last), IsOk());
  ASSERT_THAT(source->ReadSlices(0, 1, first), IsOk());
  EXPECT_TRUE(std::equal(last.begin(), last.end(), in.data.begin() + 3 * slice));
  EXPECT_TRUE(std::equal(first.begin(), first.end(), in.data.begin()));
}

INSTANTIATE_TEST_SUITE_P(
    AllFormatsAndTypes, RoundTripTest,
    ::testing::Combine(::testing::Values(FormatCase{VolumeFormat::kRaw, ".raw", false},
                                         FormatCase{VolumeFormat::kTiff, ".tif", true},
                                         FormatCase{VolumeFormat::kTiffFolder, "_slices", true},
                                         FormatCase{VolumeFormat::kNrrd, ".nrrd", true},
                                         FormatCase{VolumeFormat::kNrrdGzip, ".nrrd", true},
                                         FormatCase{VolumeFormat::kVdb, ".vdb", true},
                                         FormatCase{VolumeFormat::kHdf5, ".h5", true}),
                       ::testing::Values(DType::kUInt8, DType::kUInt16, DType::kFloat32)),
    [](const auto& info) {
      std::string name = std::get<0>(info.param).name;
      name =
          name.substr(1) + (std::get<0>(info.param).format == VolumeFormat::kNrrdGzip ? "gz" : "");
      return name + "_" + std::string(DTypeName(std::get<1>(info.param)));
    });

TEST(RawIoTest, BigEndianRoundTrip) {
  TempDir tmp;
  const DenseVolume in = Pattern(DType::kUInt16);
  const std::string path = tmp.File("be.raw");
  SM_ASSERT_OK_AND_ASSIGN(auto sink, CreateRawWriter(path, in.info, ByteOrder::kBig));
  ASSERT_THAT(WriteDense(in, *sink), IsOk());
  RawOptions o;
  o.dims = in.info.dims;
  o.dtype = DType::kUInt16;
  o.byte_order = ByteOrder::kBig;
  SM_ASSERT_OK_AND_ASSIGN(auto source, OpenRawVolume(path, o));
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume out, ReadDense(*source));
  ExpectSameVoxels(in, out);
  // Read as little-endian, the values differ: the byte order matters.
  o.byte_order = ByteOrder::kLittle;
  SM_ASSERT_OK_AND_ASSIGN(auto wrong, OpenRawVolume(path, o));
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume swapped, ReadDense(*wrong));
  EXPECT_FALSE(swapped.data == in.data);
}

TEST(RawIoTest, HeaderBytesAreSkipped) {
  TempDir tmp;
  const DenseVolume in = Pattern(DType::kUInt8);
  const std::string path = tmp.File("h.raw");
  std::string content(100, 'H');
  content.append(reinterpret_cast<const char*>(in.data.data()), in.data.size());
  ASSERT_THAT(WriteFileAtomically(path, content), IsOk());
  RawOptions o;
  o.dims = in.info.dims;
  o.header_bytes = 100;
  SM_ASSERT_OK_AND_ASSIGN(auto source, OpenRawVolume(path, o));
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume out, ReadDense(*source));
  ExpectSameVoxels(in, out);
}

TEST(RawIoTest, WrongDimsForTheFileSizeNameBothSizes) {
  TempDir tmp;
  const std::string path = tmp.File("small.raw");
  ASSERT_THAT(WriteFileAtomically(path, std::string(1000, '\0')), IsOk());
  RawOptions o;
  o.dims = {10, 10, 11};
  EXPECT_THAT(OpenRawVolume(path, o),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       ::testing::AllOf(HasSubstr(path), HasSubstr("10x10x11"), HasSubstr("1100"),
                                        HasSubstr("1000"), HasSubstr("truncated"))));
  o.dims = {10, 10, 9};
  EXPECT_THAT(OpenRawVolume(path, o),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("wrong dims or dtype")));
  o.dims = {10, 10, 5};
  o.dtype = DType::kUInt16;
  EXPECT_THAT(OpenRawVolume(path, o), IsOk());
}

TEST(RawIoTest, OverflowingAndOversizedDimsAreRefusedBeforeAllocating) {
  TempDir tmp;
  const std::string path = tmp.File("x.raw");
  ASSERT_THAT(WriteFileAtomically(path, "abc"), IsOk());
  RawOptions o;
  o.dims = {int64_t{1} << 30, int64_t{1} << 30, int64_t{1} << 30};
  VolumeLimits wide;
  wide.max_extent = int64_t{1} << 40;
  EXPECT_THAT(OpenRawVolume(path, o, wide),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("overflow")));
  EXPECT_THAT(OpenRawVolume(path, o),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("extent above the limit")));
  o.dims = {1000, 1000, 1000};
  VolumeLimits limits;
  limits.max_voxels = 1000000;
  EXPECT_THAT(OpenRawVolume(path, o, limits),
              StatusIs(absl::StatusCode::kResourceExhausted, HasSubstr("1000000")));
  o.dims = {0, 5, 5};
  EXPECT_THAT(OpenRawVolume(path, o),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("positive")));
}

TEST(RawIoTest, MissingFileIsNotFound) {
  RawOptions o;
  o.dims = {1, 1, 1};
  EXPECT_THAT(OpenRawVolume("/nonexistent/v.raw", o), StatusIs(absl::StatusCode::kNotFound));
}

TEST(VolumeOpenTest, RawNeedsDimsOrADescriptiveName) {
  TempDir tmp;
  const std::string path = tmp.File("plain.raw");
  ASSERT_THAT(WriteFileAtomically(path, std::string(8, '\0')), IsOk());
  EXPECT_THAT(OpenVolume(path), StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("--dims")));
  OpenOptions o;
  o.raw_dims = Dims{2, 2, 2};
  EXPECT_THAT(OpenVolume(path, o), IsOk());
}

TEST(VolumeOpenTest, DimsFromFileNames) {
  struct Case {
    const char* name;
    bool found;
    Dims dims;
    DType dtype;
  };
  const Case cases[] = {
      {"dpm_3fractures_100x100x100_u8.raw", true, {100, 100, 100}, DType::kUInt8},
      {"/a/b/rock_512x256x64_u16.raw", true, {512, 256, 64}, DType::kUInt16},
      {"f_3x4x5_f32.bin", true, {3, 4, 5}, DType::kFloat32},
      {"vol_7x5x4.raw", true, {7, 5, 4}, DType::kUInt8},
      {"volume.raw", false, {}, DType::kUInt8},
  };
  for (const Case& c : cases) {
    const auto named = DimsFromFileName(c.name);
    ASSERT_THAT(named, IsOk()) << c.name;
    const auto& r = *named;
    ASSERT_EQ(r.has_value(), c.found) << c.name;
    if (!c.found) continue;
    EXPECT_EQ(r->first, c.dims) << c.name;
    EXPECT_EQ(r->second, c.dtype) << c.name;
  }
}

TEST(VolumeOpenTest, ATypeTheNameGivesWronglyIsInvalidArgument) {
  EXPECT_THAT(DimsFromFileName("rock_64x64x64_i7.raw"),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("'i7'")));
  EXPECT_THAT(DimsFromFileName("rock_64x64x64_s16.raw"),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("'s16'")));
  TempDir tmp;
  const std::string path = tmp.File("v_4x4x4_i7.raw");
  ASSERT_THAT(WriteFileAtomically(path, std::string(64, '\0')), IsOk());
  EXPECT_THAT(OpenVolume(path), StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("i7")));
  OpenOptions typed;
  typed.raw_dtype = DType::kUInt8;
  EXPECT_THAT(OpenVolume(path, typed), IsOk()) << "a type given beats the name's";
}

TEST(VolumeOpenTest, UnknownExtensionAndBadSpacingAreInvalidArgument) {
  TempDir tmp;
  const std::string path = tmp.File("v.xyz");
  ASSERT_THAT(WriteFileAtomically(path, "x"), IsOk());
  EXPECT_THAT(OpenVolume(path), StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr(".xyz")));
  const std::string raw = tmp.File("v_1x1x1_u8.raw");
  ASSERT_THAT(WriteFileAtomically(raw, "x"), IsOk());
  OpenOptions o;
  o.spacing = Vec3(1, 0, 1);
  EXPECT_THAT(OpenVolume(raw, o),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("spacing")));
}

// Writes a two-page TIFF whose pages have the given sizes.
void WriteTwoPageTiff(const std::string& path, uint32_t w0, uint32_t h0, uint32_t w1, uint32_t h1,
                      uint16_t bits = 8, uint16_t format = SAMPLEFORMAT_UINT) {
  TIFF* t = TIFFOpen(path.c_str(), "w");
  ASSERT_NE(t, nullptr);
  for (auto [w, h] : {std::pair{w0, h0}, std::pair{w1, h1}}) {
    TIFFSetField(t, TIFFTAG_IMAGEWIDTH, w);
    TIFFSetField(t, TIFFTAG_IMAGELENGTH, h);
    TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, bits);
    TIFFSetField(t, TIFFTAG_SAMPLEFORMAT, format);
    TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, uint16_t{1});
    TIFFSetField(t, TIFFTAG_PHOTOMETRIC, uint16_t{PHOTOMETRIC_MINISBLACK});
    TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, h);
    std::vector<uint8_t> row(w * bits / 8, 7);
    for (uint32_t r = 0; r < h; ++r) TIFFWriteScanline(t, row.data(), r, 0);
    TIFFWriteDirectory(t);
  }
  TIFFClose(t);
}

TEST(TiffIoTest, PagesOfDifferentSizeNameThePageAndBothSizes) {
  TempDir tmp;
  const std::string path = tmp.File("mixed.tif");
  WriteTwoPageTiff(path, 8, 6, 9, 6);
  EXPECT_THAT(OpenTiffVolume(path),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       ::testing::AllOf(HasSubstr("page 1"), HasSubstr("9x6"), HasSubstr("8x6"))));
}

TEST(TiffIoTest, MinIsWhitePagesReadAsIntensity) {
  TempDir tmp;
  const std::string path = tmp.File("white.tif");
  TIFF* t = TIFFOpen(path.c_str(), "w");
  ASSERT_NE(t, nullptr);
  TIFFSetField(t, TIFFTAG_IMAGEWIDTH, 2u);
  TIFFSetField(t, TIFFTAG_IMAGELENGTH, 1u);
  TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, uint16_t{8});
  TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, uint16_t{1});
  TIFFSetField(t, TIFFTAG_PHOTOMETRIC, uint16_t{PHOTOMETRIC_MINISWHITE});
  uint8_t row[2] = {0, 200};
  TIFFWriteScanline(t, row, 0, 0);
  TIFFClose(t);
  SM_ASSERT_OK_AND_ASSIGN(auto source, OpenTiffVolume(path));
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume v, ReadDense(*source));
  EXPECT_EQ(v.At(0, 0, 0), 255);
  EXPECT_EQ(v.At(1, 0, 0), 55);
}

TEST(TiffIoTest, UnsupportedSampleTypeIsInvalidArgument) {
  TempDir tmp;
  const std::string path = tmp.File("int16.tif");
  WriteTwoPageTiff(path, 4, 4, 4, 4, 16, SAMPLEFORMAT_INT);
  EXPECT_THAT(OpenTiffVolume(path),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("16-bit signed integer")));
}

TEST(TiffIoTest, FolderSlicesOfDifferentSizeNameBothFiles) {
  TempDir tmp;
  const std::string folder = tmp.File("slices");
  VolumeInfo a;
  a.dims = {6, 5, 2};
  SM_ASSERT_OK_AND_ASSIGN(auto sink, CreateTiffFolderWriter(folder, a));
  ASSERT_THAT(WriteDense(DenseVolume::Zeros(a.dims, DType::kUInt8), *sink), IsOk());
  WriteTwoPageTiff(tmp.File("slices/slice_00002.tif"), 7, 5, 7, 5);
  EXPECT_THAT(OpenTiffFolder(folder),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       ::testing::AllOf(HasSubstr("slice_00002.tif"), HasSubstr("slice_00000.tif"),
                                        HasSubstr("7x5"), HasSubstr("6x5"))));
}

TEST(TiffIoTest, FolderSlicesAreOrderedByNumberNotByText) {
  TempDir tmp;
  const std::string folder = tmp.File("numbered");
  std::filesystem::create_directories(folder);
  for (int z : {8, 9, 10}) {
    VolumeInfo info;
    info.dims = {3, 2, 1};
    DenseVolume v = DenseVolume::Zeros(info.dims, DType::kUInt8);
    v.Set(0, 0, 0, z);
    SM_ASSERT_OK_AND_ASSIGN(auto sink,
                            CreateTiffWriter(folder + "/s" + std::to_string(z) + ".tif", info));
    ASSERT_THAT(WriteDense(v, *sink), IsOk());
  }
  SM_ASSERT_OK_AND_ASSIGN(auto source, OpenTiffFolder(folder));
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume v, ReadDense(*source));
  EXPECT_EQ(v.At(0, 0, 0), 8);
  EXPECT_EQ(v.At(0, 0, 1), 9);
  EXPECT_EQ(v.At(0, 0, 2), 10);
}

TEST(TiffIoTest, NotATiffAndEmptyFolder) {
  TempDir tmp;
  const std::string path = tmp.File("fake.tif");
  ASSERT_THAT(WriteFileAtomically(path, "this is not a tiff"), IsOk());
  EXPECT_THAT(OpenTiffVolume(path), StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr(path)));
  std::filesystem::create_directories(tmp.File("empty"));
  EXPECT_THAT(OpenTiffFolder(tmp.File("empty")), StatusIs(absl::StatusCode::kNotFound));
}

TEST(NrrdHeaderTest, TableOfHeaders) {
  struct Case {
    std::string text;
    absl::StatusCode code;
    std::string message;  // expected substring when not OK
  };
  const std::string ok = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 4 5 6\nencoding: raw\n";
  const Case cases[] = {
      {ok + "\n", absl::StatusCode::kOk, ""},
      {ok + "endian: big\nspacings: 1 2 3\n\n", absl::StatusCode::kOk, ""},
      {"NRRD0004\r\ntype: float\r\ndimension: 3\r\nsizes: 1 1 1\r\nencoding: gzip\r\n\r\n",
       absl::StatusCode::kOk, ""},
      {"PNG\n\n", absl::StatusCode::kInvalidArgument, "not a NRRD"},
      {"NRRD0004\ntype: double\ndimension: 3\nsizes: 1 1 1\nencoding: raw\n\n",
       absl::StatusCode::kInvalidArgument, "'type' = 'double'"},
      {"NRRD0004\ntype: uchar\ndimension: 2\nsizes: 1 1\nencoding: raw\n\n",
       absl::StatusCode::kInvalidArgument, "'dimension' = '2'"},
      {"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1 1 1\nencoding: bzip2\n\n",
       absl::StatusCode::kInvalidArgument, "'encoding' = 'bzip2'"},
      {"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1 x 1\nencoding: raw\n\n",
       absl::StatusCode::kInvalidArgument, "'sizes'"},
      {"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 0 1 1\nencoding: raw\n\n",
       absl::StatusCode::kInvalidArgument, "positive"},
      {"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1 1 1\n\n", absl::StatusCode::kInvalidArgument,
       "lacks 'encoding'"},
      {ok, absl::StatusCode::kOutOfRange, "no closing blank line"},
      {ok + "spacings: 1 -2 3\n\n", absl::StatusCode::kInvalidArgument, "spacings"},
      {ok + "space directions: (1,1,0) (0,1,0) (0,0,1)\n\n", absl::StatusCode::kInvalidArgument,
       "axis-aligned"},
      {ok + "garbage line\n\n", absl::StatusCode::kInvalidArgument, "garbage line"},
      {"NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2000000 2000000 2000000\nencoding: raw\n\n",
       absl::StatusCode::kInvalidArgument, "extent"},
  };
  for (const Case& c : cases) {
    const auto r = ParseNrrdHeader(c.text, "t.nrrd");
    EXPECT_EQ(r.status().code(), c.code) << c.text << "\n" << r.status();
    if (!r.ok()) EXPECT_THAT(std::string(r.status().message()), HasSubstr(c.message)) << c.text;
  }
  const auto h = ParseNrrdHeader(ok + "endian: big\nspacings: 1 2 3\n\n", "t.nrrd");
  ASSERT_THAT(h, IsOk());
  EXPECT_EQ(h->dims, (Dims{4, 5, 6}));
  EXPECT_EQ(h->byte_order, ByteOrder::kBig);
  EXPECT_EQ(h->placement.spacing.y, 2);
}

TEST(NrrdIoTest, TruncatedRawAndGzipDataAreErrorsNotCrashes) {
  TempDir tmp;
  const DenseVolume in = Pattern(DType::kUInt8, {32, 32, 8});
  for (NrrdEncoding enc : {NrrdEncoding::kRaw, NrrdEncoding::kGzip}) {
    const std::string path = tmp.File(enc == NrrdEncoding::kRaw ? "r.nrrd" : "g.nrrd");
    SM_ASSERT_OK_AND_ASSIGN(auto sink, CreateNrrdWriter(path, in.info, enc));
    ASSERT_THAT(WriteDense(in, *sink), IsOk());
    std::filesystem::resize_file(path, std::filesystem::file_size(path) - 200);
    auto source = OpenNrrdVolume(path);
    if (enc == NrrdEncoding::kRaw) {
      EXPECT_THAT(source, StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("truncated")));
      continue;
    }
    ASSERT_THAT(source, IsOk());
    EXPECT_THAT(ReadDense(**source), StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr(path)));
  }
}

TEST(NrrdIoTest, DetachedHeaderReadsItsDataFile) {
  TempDir tmp;
  const DenseVolume in = Pattern(DType::kUInt16);
  SM_ASSERT_OK_AND_ASSIGN(auto sink, CreateRawWriter(tmp.File("data.raw"), in.info));
  ASSERT_THAT(WriteDense(in, *sink), IsOk());
  ASSERT_THAT(WriteFileAtomically(tmp.File("h.nhdr"),
                                  "NRRD0004\ntype: ushort\ndimension: 3\nsizes: 7 5 4\n"
                                  "endian: little\nencoding: raw\ndata file: data.raw\n\n"),
              IsOk());
  SM_ASSERT_OK_AND_ASSIGN(auto source, OpenVolume(tmp.File("h.nhdr")));
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume out, ReadDense(*source));
  ExpectSameVoxels(in, out);
  // Detached headers that end with their file (as teem and Slicer write them): no closing
  // blank line, and none with no newline after the last line either.
  for (const char* ending : {"data file: data.raw\n", "data file: data.raw"}) {
    ASSERT_THAT(WriteFileAtomically(tmp.File("open.nhdr"),
                                    std::string("NRRD0004\ntype: ushort\ndimension: 3\nsizes: 7 5 "
                                                "4\nendian: little\nencoding: raw\n") +
                                        ending),
                IsOk());
    SM_ASSERT_OK_AND_ASSIGN(auto open, OpenVolume(tmp.File("open.nhdr")));
    SM_ASSERT_OK_AND_ASSIGN(DenseVolume read, ReadDense(*open));
    ExpectSameVoxels(in, read);
  }
  // An attached header still needs its blank line: the data cannot be told from it.
  ASSERT_THAT(WriteFileAtomically(tmp.File("attached.nrrd"),
                                  "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 1 1 1\nencoding: "
                                  "raw\n"),
              IsOk());
  EXPECT_THAT(OpenVolume(tmp.File("attached.nrrd")),
              StatusIs(absl::StatusCode::kOutOfRange, HasSubstr("no closing blank line")));
}

TEST(VdbIoTest, VoxelSetAndLabelsReadBack) {
  TempDir tmp;
  const Dims d{9, 8, 7};
  const VoxelSet set = VoxelSet::FromIndices(d, {{1, 1, 1}, {2, 1, 1}, {8, 7, 6}});
  const std::vector<int32_t> labels = {3, 3, 7};
  const std::string path = tmp.File("model.vdb");
  ASSERT_THAT(WriteVoxelSetVdb(path, set, labels, Placement()), IsOk());
  SM_ASSERT_OK_AND_ASSIGN(auto mask, OpenVdbVolume(path, "sheet"));
  EXPECT_EQ(mask->info().dims, d);
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume m, ReadDense(*mask));
  EXPECT_EQ(m.At(2, 1, 1), 1);
  EXPECT_EQ(m.At(3, 1, 1), 0);
  SM_ASSERT_OK_AND_ASSIGN(auto lab, OpenVdbVolume(path, "sheet_labels"));
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume l, ReadDense(*lab));
  EXPECT_EQ(l.At(8, 7, 6), 7);
  EXPECT_THAT(OpenVdbVolume(path, "nope"),
              StatusIs(absl::StatusCode::kNotFound, HasSubstr("nope")));
}

TEST(VdbIoTest, NotAVdbIsInvalidArgument) {
  TempDir tmp;
  const std::string path = tmp.File("x.vdb");
  ASSERT_THAT(WriteFileAtomically(path, "not vdb"), IsOk());
  EXPECT_THAT(OpenVdbVolume(path), StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr(path)));
}

TEST(VolumeSinkTest, UnfinishedWritesLeaveNoFile) {
  TempDir tmp;
  const std::string path = tmp.File("partial.raw");
  VolumeInfo info;
  info.dims = {2, 2, 2};
  {
    SM_ASSERT_OK_AND_ASSIGN(auto sink, CreateRawWriter(path, info));
    std::vector<std::byte> slice(4);
    ASSERT_THAT(sink->WriteSlices(1, slice), IsOk());
    EXPECT_THAT(sink->Finish(), StatusIs(absl::StatusCode::kFailedPrecondition));
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_FALSE(HasPartFile(tmp.path()));
  // The same for HDF5, which writes through its library.
  const std::string h5 = tmp.File("partial.h5");
  {
    SM_ASSERT_OK_AND_ASSIGN(auto sink, CreateVolumeWriter(h5, info, VolumeFormat::kHdf5));
    std::vector<std::byte> slice(4);
    ASSERT_THAT(sink->WriteSlices(1, slice), IsOk());
    EXPECT_THAT(sink->Finish(), StatusIs(absl::StatusCode::kFailedPrecondition));
  }
  EXPECT_FALSE(std::filesystem::exists(h5));
  EXPECT_FALSE(HasPartFile(tmp.path()));
}

// HDF5 label volumes are chunked and compressed: a box of mostly zeros written slab by slab
// takes a small part of its dense size, and reads back with its unit.
TEST(Hdf5WriterTest, AMostlyEmptyBoxIsSmallAndReadsBackWithItsUnit) {
  TempDir tmp;
  VolumeInfo info;
  info.dims = {300, 200, 40};
  info.dtype = DType::kUInt16;
  info.placement.spacing = {5, 5, 5};
  info.placement.unit = "um";
  DenseVolume in = DenseVolume::Zeros(info.dims, info.dtype);
  in.info = info;
  for (int z = 18; z < 21; ++z)
    for (int y = 0; y < 200; ++y)
      for (int x = 0; x < 300; ++x) in.Set(x, y, z, 1 + (x / 100));
  const std::string path = tmp.File("labels.h5");
  SM_ASSERT_OK_AND_ASSIGN(auto sink, CreateVolumeWriter(path, info, VolumeFormat::kHdf5));
  const size_t slice = 300 * 200 * 2;
  for (int z = 0; z < 40; z += 3) {  // slabs that do not line up with the chunks
    const int n = std::min(3, 40 - z);
    ASSERT_THAT(
        sink->WriteSlices(n, std::span<const std::byte>(in.data).subspan(z * slice, n * slice)),
        IsOk());
  }
  ASSERT_THAT(sink->Finish(), IsOk());
  EXPECT_LT(std::filesystem::file_size(path), in.data.size() / 50);
  SM_ASSERT_OK_AND_ASSIGN(auto source, OpenVolume(path));
  EXPECT_EQ(source->info().placement.unit, "um");
  EXPECT_NEAR(source->info().placement.spacing.y, 5, 1e-9);
  SM_ASSERT_OK_AND_ASSIGN(DenseVolume out, ReadDense(*source));
  ExpectSameVoxels(in, out);
}

}  // namespace
}  // namespace sheetmesh
