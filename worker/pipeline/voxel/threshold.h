// Thresholds for grayscale scans: Otsu's (the split of the value histogram that maximises
// the variance between the two classes), or the user's value, turned into the sheet phase
// on one side of it (open fractures are dark in CT; mineral veins bright).
#ifndef SHEETMESH_WORKER_PIPELINE_VOXEL_THRESHOLD_H_
#define SHEETMESH_WORKER_PIPELINE_VOXEL_THRESHOLD_H_

#include <cstdint>
#include <span>
#include <string>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/volume/volume_source.h"
#include "worker/pipeline/voxel/phase_selection.h"

namespace sheetmesh {

// Otsu's threshold of a histogram whose bin i holds values in [lo + i w, lo + (i + 1) w):
// the value between the classes (a bin's upper edge). `lo` when the histogram has one
// occupied bin.
double OtsuOfHistogram(std::span<const uint64_t> counts, double lo, double bin_width);

// Otsu's threshold of the whole volume: exact per value for 8- and 16-bit voxels, 4096
// bins over the value range for float32 (two passes). Reads slab by slab.
absl::StatusOr<double> OtsuThreshold(VolumeSource& source, const Progress& progress = {});

// What input.threshold says: "otsu" or a number; kInvalidArgument naming the text.
struct ThresholdSpec {
  bool otsu = false;
  double value = 0;
};
absl::StatusOr<ThresholdSpec> ParseThreshold(const std::string& text);

// The sheet phase on one side of `t`: below (value < t) or above (value >= t).
PhaseSelection SideOfThreshold(double t, bool above);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOXEL_THRESHOLD_H_
