// The VDB structure check: every scalar grid OpenVDB writes (each value type, compression,
// halves, instances) reads as written, and a file with bytes changed anywhere is a clean error
// naming it — never a signal, never gigabytes — before OpenVDB reads a byte of its tree.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "absl/strings/str_cat.h"
#include "common/file_util.h"
#include "tests/testing/bad_volumes.h"
#include "tests/testing/status_matchers.h"
#include "tests/testing/temp_dir.h"
#include "worker/pipeline/phantom/phantom.h"
#include "worker/pipeline/phantom/phantom_presets.h"
#include "worker/pipeline/volume/vdb_check.h"
#include "worker/pipeline/volume/vdb_io.h"
#include "worker/pipeline/volume/volume_open.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::IsOk;
using ::sheetmesh::testing::StatusIs;
using ::sheetmesh::testing::TempDir;
using ::testing::AllOf;
using ::testing::HasSubstr;

// Reads every slice; the first error, or the volume.
absl::StatusOr<DenseVolume> ReadAll(const std::string& path, const VolumeLimits& limits = {},
                                    const std::string& grid = "") {
  OpenOptions o;
  o.vdb_grid = grid;
  o.limits = limits;
  auto source = OpenVolume(path, o);
  if (!source.ok()) return source.status();
  return ReadDense(**source);
}

// A block of active voxels 1..40 x 3..20 x 5..30 with value 1 + (x + y + z) % 7, in a grid of
// `GridT`.
template <class GridT>
typename GridT::Ptr Block() {
  openvdb::initialize();
  auto grid = GridT::create();
  auto acc = grid->getAccessor();
  for (int z = 5; z <= 30; ++z) {
    for (int y = 3; y <= 20; ++y) {
      for (int x = 1; x <= 40; ++x) {
        acc.setValue(openvdb::Coord(x, y, z),
                     static_cast<typename GridT::ValueType>(1 + (x + y + z) % 7));
      }
    }
  }
  return grid;
}

void Write(const std::string& path, const openvdb::GridPtrVec& grids, uint32_t compression) {
  openvdb::io::File file(path);
  file.setCompression(compression);
  file.write(grids);
  file.close();
}

TEST(VdbCheckTest, EveryScalarGridTypeAndCompressionReadsAsWritten) {
  TempDir tmp;
  using openvdb::io::COMPRESS_ACTIVE_MASK;
  using openvdb::io::COMPRESS_BLOSC;
  using openvdb::io::COMPRESS_ZIP;
  const uint32_t compressions[] = {0, COMPRESS_ZIP, COMPRESS_BLOSC, COMPRESS_ACTIVE_MASK,
                                   COMPRESS_ACTIVE_MASK | COMPRESS_ZIP,
                                   COMPRESS_ACTIVE_MASK | COMPRESS_BLOSC};
  int n = 0;
  for (uint32_t c : compressions) {
    std::vector<std::pair<std::string, openvdb::GridBase::Ptr>> grids = {
        {"float", Block<openvdb::FloatGrid>()},   {"double", Block<openvdb::DoubleGrid>()},
        {"int32", Block<openvdb::Int32Grid>()},   {"int64", Block<openvdb::Int64Grid>()},
        {"bool", Block<openvdb::BoolGrid>()},     {"mask", Block<openvdb::MaskGrid>()},
        {"half", Block<openvdb::FloatGrid>()}};
    grids.back().second->setSaveFloatAsHalf(true);
    for (auto& [name, grid] : grids) {
      const std::string path = tmp.File(absl::StrCat(name, "_", c, ".vdb"));
      grid->setName(name);
      Write(path, {grid}, c);
      absl::StatusOr<DenseVolume> v = ReadAll(path);
      ASSERT_THAT(v.status(), IsOk()) << path;
      EXPECT_EQ(v->info.dims, (Dims{40, 18, 26})) << path;
      const bool flag = name == "bool" || name == "mask";
      for (const auto& [x, y, z] : {std::array<int, 3>{1, 3, 5}, {40, 20, 30}, {17, 9, 22}}) {
        const double want = flag ? 1 : 1 + (x + y + z) % 7;
        EXPECT_EQ(v->At(x - 1, y - 3, z - 5), want) << path << " at " << x << "," << y << "," << z;
      }
      ++n;
    }
  }
  EXPECT_EQ(n, 42);
}

TEST(VdbCheckTest, AnInstanceReadsItsParentsTreeAndGridsAreChosenByName) {
  TempDir tmp;
  auto parent = Block<openvdb::FloatGrid>();
  parent->setName("parent");
  auto instance = parent->copyGrid();  // shares the tree: written as an instance
  instance->setName("instance");
  auto vectors = openvdb::Vec3SGrid::create();
  vectors->setName("velocity");
  const std::string path = tmp.File("instanced.vdb");
  Write(path, {vectors, parent, instance}, openvdb::io::COMPRESS_ACTIVE_MASK |
                                               openvdb::io::COMPRESS_BLOSC);
  ASSERT_THAT(ReadVdbLayout(path).status(), IsOk());
  EXPECT_FALSE(ReadVdbLayout(path)->grids[2].instance_parent.empty());
  absl::StatusOr<DenseVolume> v = ReadAll(path, {}, "instance");
  ASSERT_THAT(v.status(), IsOk());
  EXPECT_EQ(v->At(16, 6, 17), 1 + (17 + 9 + 22) % 7);
  EXPECT_THAT(ReadAll(path).status(), IsOk());  // the first scalar grid, past the vectors
  EXPECT_THAT(ReadAll(path, {}, "velocity").status(),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("not a scalar grid")));
  EXPECT_THAT(ReadAll(path, {}, "density").status(),
              StatusIs(absl::StatusCode::kNotFound,
                       AllOf(HasSubstr("'density'"), HasSubstr("'parent'"), HasSubstr("vdb_grid"))));
}

// The audit's file: the sample phantom (128 x 112 x 96), written as the CLI's convert writes
// it (an Int32 grid, blosc and mask compression).
std::string SampleVdb(const TempDir& tmp) {
  absl::StatusOr<PhantomOptions> preset = PhantomPreset("sample");
  EXPECT_THAT(preset.status(), IsOk());
  absl::StatusOr<PhantomTruth> truth = PlanPhantom(*preset);
  EXPECT_THAT(truth.status(), IsOk());
  absl::StatusOr<DenseVolume> dense = GeneratePhantomDense(&*truth);
  EXPECT_THAT(dense.status(), IsOk());
  const std::string path = tmp.File("full.vdb");
  EXPECT_THAT(testing::WriteVolume(path, *dense), IsOk());
  return path;
}

std::string WithBytes(const std::string& from, const std::string& to,
                      const std::vector<std::pair<size_t, uint8_t>>& changes) {
  std::string bytes = *ReadFileToString(from, int64_t{1} << 30);
  for (const auto& [at, value] : changes) {
    if (at < bytes.size()) bytes[at] = static_cast<char>(value);
  }
  std::ofstream(to, std::ios::binary) << bytes;
  return to;
}

TEST(VdbCheckTest, TheAuditsChangedBytesAreInvalidArgumentNotASignalOrGigabytes) {
  TempDir tmp;
  const std::string whole = SampleVdb(tmp);
  ASSERT_THAT(ReadAll(whole).status(), IsOk());
  // Before the check: malloc(): corrupted top size (SIGABRT), a SIGSEGV, and 14.8 GB.
  const std::vector<std::pair<size_t, uint8_t>> audit = {{2167, 79}, {78941, 128}, {1357, 127}};
  for (const auto& change : audit) {
    const std::string path = WithBytes(whole, tmp.File("changed.vdb"), {change});
    VolumeLimits limits;
    limits.memory_bytes = int64_t{1} << 30;
    EXPECT_THAT(ReadAll(path, limits).status(),
                StatusIs(absl::StatusCode::kInvalidArgument,
                         AllOf(HasSubstr(path), HasSubstr("at byte"))))
        << "byte " << change.first << " set to " << int{change.second};
  }
}

TEST(VdbCheckTest, ChangedBytesAnywhereEndInAnErrorOrTheVolume) {
  TempDir tmp;
  const std::string whole = tmp.File("whole.vdb");
  ASSERT_THAT(testing::WriteVolume(whole, testing::SheetVolume({48, 40, 32})), IsOk());
  const size_t size = std::filesystem::file_size(whole);
  std::mt19937 rng(5);
  VolumeLimits limits;
  limits.memory_bytes = int64_t{256} << 20;
  int errors = 0, read = 0;
  for (int i = 0; i < 1500; ++i) {
    std::vector<std::pair<size_t, uint8_t>> changes;
    for (int k = 0, n = 1 + static_cast<int>(rng() % 4); k < n; ++k) {
      changes.push_back({rng() % size, static_cast<uint8_t>(rng())});
    }
    const std::string path = WithBytes(whole, tmp.File("mutant.vdb"), changes);
    const absl::Status st = ReadAll(path, limits).status();
    if (st.ok()) {
      ++read;
    } else {
      ++errors;
      EXPECT_THAT(st.code(), ::testing::AnyOf(absl::StatusCode::kInvalidArgument,
                                              absl::StatusCode::kResourceExhausted,
                                              absl::StatusCode::kNotFound))
          << st;
      EXPECT_THAT(st.message(), HasSubstr(path));
    }
  }
  EXPECT_GT(errors, 100);
  EXPECT_GT(read, 10);  // changed voxel values still read
}

TEST(VdbCheckTest, ATreeLargerThanTheBudgetIsResourceExhaustedBeforeItIsBuilt) {
  TempDir tmp;
  auto grid = Block<openvdb::FloatGrid>();
  auto acc = grid->getAccessor();
  for (int k = 0; k < 64; ++k) acc.setValue(openvdb::Coord(k * 4096, 0, 0), 1.0f);  // 64 roots
  grid->setName("spread");
  const std::string path = tmp.File("spread.vdb");
  Write(path, {grid}, openvdb::io::COMPRESS_ACTIVE_MASK | openvdb::io::COMPRESS_BLOSC);
  absl::StatusOr<VdbFileLayout> layout = ReadVdbLayout(path);
  ASSERT_THAT(layout.status(), IsOk());
  EXPECT_THAT(CheckVdbGrid(path, *layout, 0, int64_t{64} << 20), IsOk());
  EXPECT_THAT(CheckVdbGrid(path, *layout, 0, int64_t{4} << 20),
              StatusIs(absl::StatusCode::kResourceExhausted,
                       AllOf(HasSubstr("'spread'"), HasSubstr("budget"))));
}

}  // namespace
}  // namespace sheetmesh
