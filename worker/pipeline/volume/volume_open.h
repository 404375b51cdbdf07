// OpenVolume: picks the reader for a path (raw, TIFF file or folder, NRRD, VDB) and applies
// the user's placement overrides. Also whole-volume helpers for small volumes and tests.
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_VOLUME_OPEN_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_VOLUME_OPEN_H_

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "worker/pipeline/volume/child_reader.h"
#include "worker/pipeline/volume/raw_io.h"
#include "worker/pipeline/volume/volume_sink.h"
#include "worker/pipeline/volume/volume_source.h"

namespace sheetmesh {

// A box of voxels [lo, hi) in a volume's index space.
struct VoxelRegion {
  Index3 lo;
  Index3 hi;
  Dims dims() const { return {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z}; }
  std::string ToString() const;  // "X0,Y0,Z0,X1,Y1,Z1"
  friend bool operator==(const VoxelRegion&, const VoxelRegion&) = default;
};

struct OpenOptions {
  std::string format;              // "", "raw", "tiff", "nrrd", "vdb" ("" = by name)
  std::optional<Dims> raw_dims;    // raw: required unless the name says "_NxNxN_u8"
  std::optional<DType> raw_dtype;  // raw: default uint8 or the name's "_u8/_u16/_f32"
  ByteOrder raw_byte_order = ByteOrder::kLittle;
  int64_t raw_header_bytes = 0;
  std::string vdb_grid;         // vdb: grid name ("" = first scalar grid)
  std::optional<Vec3> spacing;  // overrides the file's spacing
  std::optional<Vec3> origin;   // overrides the file's origin
  std::string unit;             // overrides the file's length unit when set
  // Read only this box of the volume (a region of interest, a brick): the source's dims are
  // the region's and its origin the region's first voxel's; only its slices are read.
  std::optional<VoxelRegion> region;
  VolumeLimits limits;
  // With a program, formats a third-party library parses (ReadByLibrary) are read by a
  // child process of it, within limits (child_reader.h).
  ChildReaderOptions child_reader;
};

// The reader OpenVolume takes for `path`: options.format, or the one its name (or being a
// folder) tells ("raw", "tiff", "nrrd", "hdf5", "folder", ...). kInvalidArgument naming the
// extension when neither tells.
absl::StatusOr<std::string> InputFormatOf(const std::string& path, const OpenOptions& options);

// Opens `path`: a folder reads as TIFF slices; otherwise the extension decides (.raw .bin
// .dat .img: raw; .tif .tiff: TIFF; .nrrd .nhdr: NRRD; .vdb: OpenVDB) unless
// options.format says. kInvalidArgument for an unknown extension or a raw file without dims
// (the message says how to give them).
absl::StatusOr<std::unique_ptr<VolumeSource>> OpenVolume(const std::string& path,
                                                         const OpenOptions& options = {});

// `source` seen through `region`: dims the region's, origin moved to its first voxel, slices
// read one at a time and cut to the region's rows. kInvalidArgument, naming input.region, the
// value and the volume's dims, unless the region is non-empty and inside the volume.
absl::StatusOr<std::unique_ptr<VolumeSource>> OpenRegion(std::unique_ptr<VolumeSource> source,
                                                         const VoxelRegion& region);

// Dims and dtype encoded in a file name like "rock_100x100x100_u8.raw"; nullopt if none.
// kInvalidArgument when the name gives a type that is not u8, u16 or f32 ("_i7").
absl::StatusOr<std::optional<std::pair<Dims, DType>>> DimsFromFileName(const std::string& path);

// A whole volume in memory: for small volumes, tests and the phantom's sample.
struct DenseVolume {
  VolumeInfo info;
  std::vector<std::byte> data;  // x fastest, native byte order

  static DenseVolume Zeros(const Dims& dims, DType dtype);
  template <class T>
  T* as() {
    return reinterpret_cast<T*>(data.data());
  }
  template <class T>
  const T* as() const {
    return reinterpret_cast<const T*>(data.data());
  }
  // The value at (x, y, z) as a double.
  double At(int64_t x, int64_t y, int64_t z) const;
  void Set(int64_t x, int64_t y, int64_t z, double value);
};

// Reads all of `source`. kResourceExhausted above `max_bytes`.
absl::StatusOr<DenseVolume> ReadDense(VolumeSource& source, int64_t max_bytes = int64_t{4} << 30);
// Writes all of `volume` through `sink` and finishes it.
absl::Status WriteDense(const DenseVolume& volume, VolumeSink& sink);

// Output formats for CreateVolumeWriter.
enum class VolumeFormat { kRaw, kTiff, kTiffFolder, kNrrd, kNrrdGzip, kVdb, kHdf5 };
absl::StatusOr<VolumeFormat> ParseVolumeFormat(absl::string_view name);
// `name` parsed, or when it is empty the format `path`'s extension names (.tif/.tiff, .nrrd,
// .vdb, .h5/.hdf5), raw otherwise.
absl::StatusOr<VolumeFormat> OutputVolumeFormat(absl::string_view name, const std::string& path);
absl::StatusOr<std::unique_ptr<VolumeSink>> CreateVolumeWriter(const std::string& path,
                                                               const VolumeInfo& info,
                                                               VolumeFormat format);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_VOLUME_OPEN_H_
