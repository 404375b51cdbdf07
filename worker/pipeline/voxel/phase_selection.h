// Phase selection: which voxels of an image are the sheet phase S (fractures, veins) —
// by label set or intensity window — read slab by slab into a sparse VoxelSet, so memory
// follows the selected voxels, not the box (ALGORITHM §0).
#ifndef SHEETMESH_WORKER_PIPELINE_VOXEL_PHASE_SELECTION_H_
#define SHEETMESH_WORKER_PIPELINE_VOXEL_PHASE_SELECTION_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "common/progress.h"
#include "worker/pipeline/volume/volume_source.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

struct PhaseSelection {
  enum class Mode { kNonZero, kLabels, kWindow };
  Mode mode = Mode::kNonZero;  // default: every non-zero voxel (binary segmentations)
  std::vector<double> labels;  // kLabels: value equals one of these
  double lo = 0.0;             // kWindow: lo <= value <= hi
  double hi = 0.0;

  static PhaseSelection NonZero() { return {}; }
  static PhaseSelection Labels(std::vector<double> labels);
  static PhaseSelection Window(double lo, double hi);
  // "nonzero", "labels=2,3" or "window=100:200".
  std::string ToString() const;
};

// Parses the forms ToString() writes; also a bare "2,3" (labels) or "100:200" (window).
// kInvalidArgument naming the text otherwise, or when lo > hi.
absl::StatusOr<PhaseSelection> ParsePhaseSelection(absl::string_view text);

// Statistics gathered while selecting, for messages and reports.
struct SelectionStats {
  double min_value = 0;  // over all voxels of the box (NaN skipped; min > max when none is
  double max_value = 0;  // a number)
  // "values range from LO to HI", or that the volume holds no number at all.
  std::string RangeText() const;
  uint64_t selected = 0;
  uint64_t outside_mask = 0;  // selected voxels dropped by the mask
};

// Reads `source` slab by slab and returns the voxels matching `selection`, restricted to
// `mask` when it is not null. kInvalidArgument if the mask's dims differ; reader errors
// pass through; kCancelled if `progress` asks. An empty result is not an error here (the
// caller decides); `stats` says what values the volume held.
absl::StatusOr<VoxelSet> SelectPhase(VolumeSource& source, const PhaseSelection& selection,
                                     const VoxelSet* mask = nullptr,
                                     SelectionStats* stats = nullptr,
                                     const Progress& progress = {});

// kInvalidArgument "FILE: selection S matched no voxel (values range from A to B)" when the
// set is empty, OK otherwise.
absl::Status CheckNotEmpty(const VoxelSet& set, const VolumeInfo& info,
                           const PhaseSelection& selection, const SelectionStats& stats);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOXEL_PHASE_SELECTION_H_
