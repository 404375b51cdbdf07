// SheetInput: everything that says where a volume is and which voxels are the sheet phase;
// LoadSheetPhase turns it into the sparse sheet set (and the rock mask when given).
#ifndef SHEETMESH_WORKER_PIPELINE_VOXEL_SHEET_INPUT_H_
#define SHEETMESH_WORKER_PIPELINE_VOXEL_SHEET_INPUT_H_

#include <optional>
#include <string>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/volume/volume_open.h"
#include "worker/pipeline/voxel/grey_volume.h"
#include "worker/pipeline/voxel/phase_selection.h"
#include "worker/pipeline/voxel/sheetness.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

struct SheetInput {
  std::string path;          // the volume (file or TIFF folder)
  OpenOptions open;          // format, raw dims, placement overrides, limits
  PhaseSelection selection;  // the sheet phase S (default: non-zero voxels)
  std::string threshold;     // grayscale: "otsu" or a number ("" = none); the phase
                             // is the voxels below it (above with threshold_above)
  bool threshold_above = false;
  std::string mask_path;          // optional rock mask volume ("" = none)
  PhaseSelection mask_selection;  // rock voxels of the mask volume (default: non-zero)
  bool mask_from_volume = false;  // take the mask from `path` itself with mask_selection
};

struct SheetPhase {
  VolumeInfo info;               // of the volume (placement included)
  VoxelSet sheet;                // S, restricted to the mask when there is one
  std::optional<VoxelSet> mask;  // rock voxels, when a mask was given
  SelectionStats stats;
  PhaseSelection selection;         // the selection used (the threshold's, when one)
  std::optional<double> threshold;  // the threshold used (Otsu's value when "otsu")
  double read_seconds = 0;          // wall time of reading and selecting
};

// The sheet phase found on grey levels (input.grey), with what it was found on.
struct GreySheetPhase {
  SheetPhase phase;  // the sheets found, the volume's info
  GreyVolume grey;   // kept for the apertures
  GreyLevels levels;
  SheetnessStats sheetness;
};

// Reads the volume's grey levels, measures the levels `given` ([void, rock], or empty) does
// not give, and finds the sheets (sheetness.h). kInvalidArgument for a mask or a selection
// beside it (input.grey is the selection), for levels that are not two numbers, for a
// volume without contrast or with only a few values (MeasureGreyLevels), and when no sheet
// is found; reader errors pass through; kCancelled if asked.
absl::StatusOr<GreySheetPhase> LoadGreySheetPhase(const SheetInput& input,
                                                  const std::vector<double>& given,
                                                  const SheetnessOptions& sheetness,
                                                  const Progress& progress = {});

// Opens the volume (and mask), selects S slab by slab (after a pass for Otsu's threshold
// when asked). kInvalidArgument when S is empty (the message names the file, the selection
// and the value range), when the default selection or Otsu's side makes S most of the
// volume (or mask), or when the mask's dims differ; reader errors pass through;
// kCancelled if asked.
absl::StatusOr<SheetPhase> LoadSheetPhase(const SheetInput& input, const Progress& progress = {});

// The selection `input` states without reading the volume: its labels or window, or the
// side of a threshold given as a number, or of "otsu" when `otsu` (its value, found
// before) is given (then *threshold is it). kInvalidArgument for "otsu" without it.
absl::StatusOr<PhaseSelection> StatedSelection(const SheetInput& input,
                                               std::optional<double>* threshold,
                                               std::optional<double> otsu = std::nullopt);

// The checks LoadSheetPhase makes of what it selected (the errors above): for a phase
// selected elsewhere (by bricks).
absl::Status CheckSheetPhase(const SheetInput& input, const SheetPhase& phase);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOXEL_SHEET_INPUT_H_
