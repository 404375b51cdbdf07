#include "tests/fuzz/fuzz_targets.h"

#include <unistd.h>

#include <string>

#include "common/file_util.h"
#include "worker/pipeline/volume/nrrd_io.h"
#include "worker/pipeline/volume/volume_open.h"
#include "worker/pipeline/voxel/phase_selection.h"

namespace sheetmesh::fuzz {
namespace {

VolumeLimits SmallLimits() {
  VolumeLimits l;
  l.max_voxels = 1 << 20;
  l.max_extent = 1 << 12;
  return l;
}

std::string TempPath(const char* ext) {
  return "/tmp/sheetmesh_fuzz_" + std::to_string(::getpid()) + ext;
}

}  // namespace

void FuzzNrrdHeader(const uint8_t* data, size_t size) {
  const absl::string_view text(reinterpret_cast<const char*>(data), size);
  (void)ParseNrrdHeader(text, "fuzz.nrrd", SmallLimits());
}

void FuzzVolumeFile(const uint8_t* data, size_t size) {
  if (size < 4) return;
  const int kind = data[0] % 3;
  OpenOptions options;
  options.limits = SmallLimits();
  const char* ext = kind == 0 ? ".raw" : (kind == 1 ? ".nrrd" : ".tif");
  if (kind == 0) {
    options.raw_dims = Dims{1 + data[1] % 64, 1 + data[2] % 64, 1 + data[3] % 64};
    options.raw_dtype = static_cast<DType>(data[1] % 3);
  }
  const std::string path = TempPath(ext);
  if (!WriteFileAtomically(path,
                           absl::string_view(reinterpret_cast<const char*>(data) + 4, size - 4))
           .ok()) {
    return;
  }
  auto source = OpenVolume(path, options);
  if (source.ok()) {
    const Dims d = (*source)->info().dims;
    std::vector<std::byte> slice(static_cast<size_t>(d.nx * d.ny) *
                                 BytesPerVoxel((*source)->info().dtype));
    for (int64_t z = 0; z < d.nz; ++z) {
      if (!(*source)->ReadSlices(z, 1, slice).ok()) break;
    }
    (void)SelectPhase(**source, PhaseSelection::NonZero());
  }
  ::unlink(path.c_str());
}

void FuzzTextParsers(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  (void)ParsePhaseSelection(text);
  (void)DimsFromFileName(text).ok();
  (void)ParseDType(text);
  (void)ParseByteOrder(text);
}

}  // namespace sheetmesh::fuzz
