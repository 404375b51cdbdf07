// Volume files that are wrong in the ways the readers must survive: header bombs, files cut
// short, headers that name files outside the allowed roots, grayscale floats read as
// segmentations. Shared by the readers' tests and the service's hardening table.
#ifndef SHEETMESH_TESTS_TESTING_BAD_VOLUMES_H_
#define SHEETMESH_TESTS_TESTING_BAD_VOLUMES_H_

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/file_util.h"
#include "worker/pipeline/volume/raw_io.h"
#include "worker/pipeline/volume/tiff_io.h"
#include "worker/pipeline/volume/vdb_io.h"
#include "worker/pipeline/volume/volume_open.h"

namespace sheetmesh::testing {

// A one-page little-endian TIFF of 8-bit samples whose header claims width x height with
// one strip of `strip_bytes` bytes (zeros; deflate-compressed when `deflate`, which makes
// the claim look plausible to a reader that trusts compression). About 17 KB.
inline std::string TiffClaiming(uint32_t width, uint32_t height, bool deflate = false,
                                uint32_t strip_bytes = 17000) {
  std::string out;
  auto u16 = [&](uint16_t v) { out.append(reinterpret_cast<const char*>(&v), 2); };
  auto u32 = [&](uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  out = "II";
  u16(42);
  u32(8);  // the first IFD
  struct Entry {
    uint16_t tag, type;
    uint32_t value;
  };
  const uint32_t data_at = 8 + 2 + 9 * 12 + 4;
  const std::vector<Entry> entries = {
      {256, 4, width},      {257, 4, height},  {258, 3, 8}, {259, 3, deflate ? 8u : 1u},
      {262, 3, 1},          {273, 4, data_at}, {277, 3, 1}, {278, 4, height},
      {279, 4, strip_bytes}};
  u16(static_cast<uint16_t>(entries.size()));
  for (const Entry& e : entries) {
    u16(e.tag);
    u16(e.type);
    u32(1);
    if (e.type == 3) {
      u16(static_cast<uint16_t>(e.value));
      u16(0);
    } else {
      u32(e.value);
    }
  }
  u32(0);  // no next IFD
  out.append(strip_bytes, '\0');
  return out;
}

// Keeps the first `fraction` of the file.
inline void CutFile(const std::string& path, double fraction) {
  const auto size = std::filesystem::file_size(path);
  std::filesystem::resize_file(path, static_cast<uintmax_t>(size * fraction));
}

// A volume with a few sheets, as a TIFF stack of dims.nz pages.
inline DenseVolume SheetVolume(Dims dims) {
  DenseVolume v = DenseVolume::Zeros(dims, DType::kUInt8);
  for (int64_t z = 0; z < dims.nz; ++z) {
    for (int64_t y = 0; y < dims.ny; ++y) {
      for (int64_t x = 0; x < dims.nx; ++x) {
        if (x == dims.nx / 2 || x == dims.nx / 2 + 1 || y == (x + z) % dims.ny) v.Set(x, y, z, 255);
      }
    }
  }
  return v;
}

inline absl::Status WriteVolume(const std::string& path, const DenseVolume& v) {
  std::unique_ptr<VolumeSink> sink;
  if (path.ends_with(".tif")) {
    auto s = CreateTiffWriter(path, v.info);
    if (!s.ok()) return s.status();
    sink = std::move(*s);
  } else if (path.ends_with(".vdb")) {
    auto s = CreateVdbWriter(path, v.info);
    if (!s.ok()) return s.status();
    sink = std::move(*s);
  } else {
    auto s = CreateRawWriter(path, v.info);
    if (!s.ok()) return s.status();
    sink = std::move(*s);
  }
  return WriteDense(v, *sink);
}

// A detached NRRD header naming `data_file` (the audit's /etc/passwd), 8^3 uchar voxels
// taken from the file's last 512 bytes.
inline std::string HeaderNaming(const std::string& data_file) {
  return absl::StrCat(
      "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 8 8 8\nencoding: raw\nbyte skip: -1\n"
      "data file: ",
      data_file, "\n\n");
}

// A float32 grayscale volume (a CT scan, not a segmentation): values 10..250, a dark
// sheet of 3 in the middle; raw, named for its dims.
inline std::string WriteGrayscale(const std::string& dir, int n) {
  const std::string path = absl::StrCat(dir, "/gray_", n, "x", n, "x", n, "_f32.raw");
  std::vector<float> v(static_cast<size_t>(n) * n * n);
  for (size_t i = 0; i < v.size(); ++i) v[i] = 10 + float(i * 7919 % 240);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y) v[(size_t(z) * n + y) * n + n / 2] = 3;
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(float));
  return path;
}

// A float32 volume of NaN with one plane of 1.0: NaN must never count as sheet.
inline std::string WriteNanVolume(const std::string& dir, int n) {
  const std::string path = absl::StrCat(dir, "/nan_", n, "x", n, "x", n, "_f32.raw");
  std::vector<float> v(static_cast<size_t>(n) * n * n, std::numeric_limits<float>::quiet_NaN());
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y) v[(size_t(z) * n + y) * n + n / 2] = 1.0f;
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(float));
  return path;
}

}  // namespace sheetmesh::testing

#endif  // SHEETMESH_TESTS_TESTING_BAD_VOLUMES_H_
