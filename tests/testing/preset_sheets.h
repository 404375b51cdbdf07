// The sheets of a phantom preset (phantom_presets.h) as a voxel set or a raw file, for tests
// that need realistic sheets: rough walls, crossings, holes, vugs, grazing contacts with the
// box.
#ifndef SHEETMESH_TESTS_TESTING_PRESET_SHEETS_H_
#define SHEETMESH_TESTS_TESTING_PRESET_SHEETS_H_

#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "tests/testing/temp_dir.h"
#include "worker/pipeline/phantom/phantom.h"
#include "worker/pipeline/phantom/phantom_presets.h"
#include "worker/pipeline/volume/raw_io.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh::testing {

// The sheet voxels (no specks) of preset `name` drawn in a box of `dims`.
inline VoxelSet PresetSheets(const std::string& name, const Dims& dims) {
  absl::StatusOr<PhantomOptions> o = PhantomPreset(name);
  EXPECT_TRUE(o.ok()) << o.status();
  o->num_specks = 0;
  o->dims = dims;
  absl::StatusOr<PhantomTruth> t = PlanPhantom(*o);
  EXPECT_TRUE(t.ok()) << t.status();
  absl::StatusOr<DenseVolume> v = GeneratePhantomDense(&*t);
  EXPECT_TRUE(v.ok()) << v.status();
  VoxelSet::Builder b(o->dims);
  for (int z = 0; z < o->dims.nz; ++z)
    for (int y = 0; y < o->dims.ny; ++y)
      for (int x = 0; x < o->dims.nx; ++x)
        if (v->At(x, y, z) != 0) b.AddVoxel(x, y, z);
  return std::move(b).Build();
}

// Preset `name`'s phantom (specks and all) at `dims` (its own without), written into `tmp`
// as a raw file named with its dims (name_NXxNYxNZ_u8.raw); returns its path.
inline std::string PresetRawFile(const TempDir& tmp, const std::string& name,
                                 std::optional<Dims> dims = std::nullopt) {
  absl::StatusOr<PhantomOptions> o = PhantomPreset(name);
  EXPECT_TRUE(o.ok()) << o.status();
  if (dims) o->dims = *dims;
  absl::StatusOr<PhantomTruth> truth = PlanPhantom(*o);
  EXPECT_TRUE(truth.ok()) << truth.status();
  const std::string path = tmp.File(name + "_" + o->dims.ToString() + "_u8.raw");
  VolumeInfo info;
  info.dims = o->dims;
  auto sink = CreateRawWriter(path, info);
  EXPECT_TRUE(sink.ok()) << sink.status();
  EXPECT_TRUE(GeneratePhantom(&*truth, **sink).ok());
  return path;
}

}  // namespace sheetmesh::testing

#endif  // SHEETMESH_TESTS_TESTING_PRESET_SHEETS_H_
