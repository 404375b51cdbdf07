// Grey levels as the scanner gave them (beyond the paper): the volume read densely in its
// own voxel type, and the grey levels of the rock and of the void (empty space) measured from its
// histogram or given, with the noise about the rock's level. What sheet detection on grey
// levels (sheetness.h) and the aperture from missing attenuation (surface/grey_apertures.h)
// start from.
#ifndef SHEETMESH_WORKER_PIPELINE_VOXEL_GREY_VOLUME_H_
#define SHEETMESH_WORKER_PIPELINE_VOXEL_GREY_VOLUME_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "common/types.h"
#include "worker/pipeline/volume/volume_source.h"

namespace sheetmesh {

struct GreyVolume {
  Dims dims;
  // One of these holds the levels, x fastest, then y, then z: an 8- or 16-bit scan as it
  // came (a byte or two a voxel, what a volume at the paper's scale can afford), a float
  // scan or a volume made in memory as floats.
  std::vector<uint8_t> values8;
  std::vector<uint16_t> values16;
  std::vector<float> values;

  size_t size() const {
    return !values8.empty() ? values8.size() : !values16.empty() ? values16.size() : values.size();
  }
  float Value(size_t i) const {
    if (!values8.empty()) return values8[i];
    if (!values16.empty()) return values16[i];
    return values[i];
  }
  float At(int64_t x, int64_t y, int64_t z) const {
    return Value(static_cast<size_t>((z * dims.ny + y) * dims.nx + x));
  }
  // Trilinear between voxel centres (voxel (x, y, z) is at (x, y, z)); points outside take
  // the nearest voxel's value.
  double Sample(const Vec3& p) const;
  // Voxels [begin, begin + count) (by linear index) as floats into `out`.
  void CopyValues(size_t begin, size_t count, float* out) const;
};

// Reads every slice of `source`: 8- and 16-bit voxels as they are, float ones as floats.
// kResourceExhausted (naming the size) when the volume does not fit `limits`' memory budget; reader
// errors pass through; kCancelled if asked.
absl::StatusOr<GreyVolume> ReadGreyVolume(VolumeSource& source, const VolumeLimits& limits,
                                          const Progress& progress = {});

// The grey level of the rock (the matrix, the histogram's main peak) and of the void, and
// the noise: the spread of the rock's grey levels about its peak (standard deviation).
struct GreyLevels {
  double rock = 0;
  double void_level = 0;
  double noise = 0;
  bool rock_measured = false;  // false: given
  bool void_measured = false;
  // Why apertures cannot be measured from these levels ("" when they can): no void phase in
  // the histogram and none given, or a contrast under three times the noise.
  std::string problem;

  double contrast() const { return rock - void_level; }
  // Contrast to noise.
  double cnr() const { return noise > 0 ? contrast() / noise : 0.0; }
  nlohmann::json Fields() const;
};

// Measures the levels `given` leaves out ([void, rock]; either may be absent) from the
// histogram of `grey`: the rock at the highest peak, the void at the darkest peak holding at
// least a thousandth of the voxels and standing clear of the rock's noise, the noise from
// the rock peak's half width. kInvalidArgument naming `path` for a volume of one value (no
// contrast at all) and for one of a few integer values (a label volume: input.labels reads
// it), and when given levels put the void above the rock.
absl::StatusOr<GreyLevels> MeasureGreyLevels(const GreyVolume& grey,
                                             std::optional<double> given_void,
                                             std::optional<double> given_rock,
                                             const std::string& path);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOXEL_GREY_VOLUME_H_
