#include "tests/fuzz/fuzz_targets.h"

#include <unistd.h>

#include <filesystem>
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
  l.memory_bytes = int64_t{64} << 20;
  // As a volume sent to the server: it may name no other file.
  l.confine_named_files = true;
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

namespace {

// Writes the bytes as a file with `ext`, opens it and reads every slice, then selects its
// phase as the pipeline would.
void OpenAndRead(absl::string_view bytes, const char* ext, OpenOptions options) {
  options.limits = SmallLimits();
  const std::string path = TempPath(ext);
  if (!WriteFileAtomically(path, bytes).ok()) return;
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

absl::string_view Bytes(const uint8_t* data, size_t size) {
  return absl::string_view(reinterpret_cast<const char*>(data), size);
}

}  // namespace

void FuzzTiffFile(const uint8_t* data, size_t size) { OpenAndRead(Bytes(data, size), ".tif", {}); }

void FuzzNrrdFile(const uint8_t* data, size_t size) { OpenAndRead(Bytes(data, size), ".nrrd", {}); }

void FuzzVdbFile(const uint8_t* data, size_t size) { OpenAndRead(Bytes(data, size), ".vdb", {}); }

void FuzzRawFile(const uint8_t* data, size_t size) {
  if (size < 3) return;
  OpenOptions options;
  options.raw_dims = Dims{1 + data[0] % 64, 1 + data[1] % 64, 1 + data[2] % 64};
  options.raw_dtype = static_cast<DType>(data[0] % 3);
  OpenAndRead(Bytes(data + 3, size - 3), ".raw", options);
}

void FuzzHdf5File(const uint8_t* data, size_t size) { OpenAndRead(Bytes(data, size), ".h5", {}); }

void FuzzNpyFile(const uint8_t* data, size_t size) { OpenAndRead(Bytes(data, size), ".npy", {}); }

void FuzzDicomFile(const uint8_t* data, size_t size) { OpenAndRead(Bytes(data, size), ".dcm", {}); }

void FuzzNiftiFile(const uint8_t* data, size_t size) { OpenAndRead(Bytes(data, size), ".nii", {}); }

namespace {

// The bytes as the one slice of a folder.
void OpenSliceFolder(absl::string_view bytes, const char* ext) {
  const std::string dir = TempPath(".slices");
  std::filesystem::create_directories(dir);
  const std::string file = dir + "/slice_0000" + ext;
  if (WriteFileAtomically(file, bytes).ok()) {
    OpenOptions options;
    options.limits = SmallLimits();
    auto source = OpenVolume(dir, options);
    if (source.ok()) {
      const Dims d = (*source)->info().dims;
      std::vector<std::byte> slice(static_cast<size_t>(d.nx * d.ny) *
                                   BytesPerVoxel((*source)->info().dtype));
      for (int64_t z = 0; z < d.nz; ++z) {
        if (!(*source)->ReadSlices(z, 1, slice).ok()) break;
      }
    }
  }
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
}

}  // namespace

void FuzzJpegFile(const uint8_t* data, size_t size) { OpenSliceFolder(Bytes(data, size), ".jpg"); }

void FuzzPngFile(const uint8_t* data, size_t size) { OpenSliceFolder(Bytes(data, size), ".png"); }

void FuzzTextParsers(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  (void)ParsePhaseSelection(text);
  (void)DimsFromFileName(text).ok();
  (void)ParseDType(text);
  (void)ParseByteOrder(text);
}

}  // namespace sheetmesh::fuzz
