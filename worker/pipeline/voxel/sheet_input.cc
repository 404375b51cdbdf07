#include "worker/pipeline/voxel/sheet_input.h"

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/status_macros.h"
#include "worker/pipeline/voxel/threshold.h"

namespace sheetmesh {
namespace {

// The default sheet phase (every non-zero voxel) suits a segmented volume. A float volume
// read that way whose "sheet" is most of the box is a grayscale scan that needed its phase
// given: refused, rather than meshed as one block.
absl::Status CheckNotGrayscale(const SheetInput& input, const SheetPhase& phase) {
  if (phase.selection.mode != PhaseSelection::Mode::kNonZero) return absl::OkStatus();
  const int64_t voxels = phase.info.dims.num_voxels();
  if (voxels <= 0 || 2 * static_cast<int64_t>(phase.stats.selected) <= voxels) {
    return absl::OkStatus();
  }
  return absl::InvalidArgumentError(absl::StrCat(
      input.path, ": a ", DTypeName(phase.info.dtype),
      " volume read with the default sheet phase (every non-zero voxel) makes ",
      std::llround(100.0 * phase.stats.selected / voxels), "% of its ", voxels, " voxels sheet (",
      phase.stats.RangeText(),
      "); a grayscale scan is meshed as it came with --grey (input.grey: sheets found on "
      "the grey levels, apertures from the attenuation they miss; --grey_levels=VOID,ROCK "
      "where they are known), or segmented with its sheet phase given: input.threshold, "
      "input.labels or input.window (--threshold=otsu for the dark phase, with "
      "--threshold_above for the bright; --threshold=V; --labels=V; --window=LO:HI)"));
}

// Otsu's threshold splits the histogram in two, and either side may be the larger: on a
// segmented volume (0 and 255) the dark side is the rock. A phase that is most of the
// volume is no sheet: refused, naming the other side.
absl::Status CheckOtsuMinority(const SheetInput& input, const SheetPhase& phase) {
  if (input.threshold != "otsu" || !phase.threshold) return absl::OkStatus();
  const int64_t voxels =
      phase.mask ? static_cast<int64_t>(phase.mask->size()) : phase.info.dims.num_voxels();
  if (voxels <= 0 || 2 * static_cast<int64_t>(phase.stats.selected) <= voxels) {
    return absl::OkStatus();
  }
  return absl::InvalidArgumentError(absl::StrCat(
      input.path, ": Otsu's threshold ", *phase.threshold, " makes ",
      std::llround(100.0 * phase.stats.selected / voxels), "% of the ", phase.mask ? "mask's " : "",
      voxels, " voxels (those ", input.threshold_above ? "at or above" : "below",
      " it) the sheet phase, and sheets are the minor phase: take the other side "
      "(--threshold_above=",
      input.threshold_above ? "false" : "true", "), or for a segmented volume --labels=V"));
}

}  // namespace

absl::StatusOr<PhaseSelection> StatedSelection(const SheetInput& input,
                                               std::optional<double>* threshold,
                                               std::optional<double> otsu) {
  if (input.threshold.empty()) return input.selection;
  SM_ASSIGN_OR_RETURN(const ThresholdSpec spec, ParseThreshold(input.threshold));
  if (spec.otsu && !otsu) {
    return absl::InvalidArgumentError(
        "input.threshold = otsu is found on the volume's histogram, not stated: give its value");
  }
  *threshold = spec.otsu ? *otsu : spec.value;
  return SideOfThreshold(**threshold, input.threshold_above);
}

absl::Status CheckSheetPhase(const SheetInput& input, const SheetPhase& phase) {
  SM_RETURN_IF_ERROR(CheckNotEmpty(phase.sheet, phase.info, phase.selection, phase.stats));
  SM_RETURN_IF_ERROR(CheckNotGrayscale(input, phase));
  return CheckOtsuMinority(input, phase);
}

absl::StatusOr<SheetPhase> LoadSheetPhase(const SheetInput& input, const Progress& progress) {
  const absl::Time start = absl::Now();
  SheetPhase out;
  const bool has_mask = !input.mask_path.empty() || input.mask_from_volume;
  if (has_mask) {
    const std::string& mpath = input.mask_from_volume ? input.path : input.mask_path;
    SM_ASSIGN_OR_RETURN(auto msource, OpenVolume(mpath, input.open));
    SelectionStats mstats;
    SM_ASSIGN_OR_RETURN(VoxelSet mask, SelectPhase(*msource, input.mask_selection, nullptr, &mstats,
                                                   progress.Sub(0, 0.5)));
    SM_RETURN_IF_ERROR(CheckNotEmpty(mask, msource->info(), input.mask_selection, mstats));
    out.mask = std::move(mask);
  }
  SM_ASSIGN_OR_RETURN(auto source, OpenVolume(input.path, input.open));
  out.info = source->info();
  out.selection = input.selection;
  Progress select = has_mask ? progress.Sub(0.5, 1) : progress;
  if (!input.threshold.empty()) {
    SM_ASSIGN_OR_RETURN(const ThresholdSpec spec, ParseThreshold(input.threshold));
    double t = spec.value;
    if (spec.otsu) {
      SM_ASSIGN_OR_RETURN(t, OtsuThreshold(*source, select.Sub(0, 0.5)));
      select = select.Sub(0.5, 1);
    }
    out.threshold = t;
    out.selection = SideOfThreshold(t, input.threshold_above);
  }
  SM_ASSIGN_OR_RETURN(out.sheet, SelectPhase(*source, out.selection,
                                             out.mask ? &*out.mask : nullptr, &out.stats, select));
  SM_RETURN_IF_ERROR(CheckSheetPhase(input, out));
  out.read_seconds = absl::ToDoubleSeconds(absl::Now() - start);
  return out;
}

absl::StatusOr<GreySheetPhase> LoadGreySheetPhase(const SheetInput& input,
                                                  const std::vector<double>& given,
                                                  const SheetnessOptions& sheetness,
                                                  const Progress& progress) {
  const absl::Time start = absl::Now();
  if (!input.mask_path.empty() || input.mask_from_volume) {
    return absl::InvalidArgumentError(
        "input.grey finds the sheets in the whole volume: input.mask is not taken with it");
  }
  if (!given.empty() && given.size() != 2) {
    return absl::InvalidArgumentError(absl::StrCat("grey.levels holds ", given.size(),
                                                   " numbers: give two, [VOID, ROCK], or none"));
  }
  GreySheetPhase out;
  SM_ASSIGN_OR_RETURN(auto source, OpenVolume(input.path, input.open));
  out.phase.info = source->info();
  SM_ASSIGN_OR_RETURN(out.grey, ReadGreyVolume(*source, input.open.limits, progress.Sub(0, 0.3)));
  std::optional<double> void_level, rock;
  if (given.size() == 2) {
    void_level = given[0];
    rock = given[1];
  }
  SM_ASSIGN_OR_RETURN(out.levels, MeasureGreyLevels(out.grey, void_level, rock, input.path));
  SM_ASSIGN_OR_RETURN(out.phase.sheet,
                      DetectSheets(out.grey, sheetness, &out.sheetness, progress.Sub(0.3, 1)));
  if (out.phase.sheet.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(
        input.path, ": input.grey found no sheet (no voxel's sheetness reached grey.high = ",
        sheetness.high, " times its noise; the rock at ", out.levels.rock, ", noise ",
        out.levels.noise, "): lower grey.high, or the sheets are brighter than the rock"));
  }
  out.phase.stats.selected = out.phase.sheet.size();
  out.phase.read_seconds = absl::ToDoubleSeconds(absl::Now() - start);
  return out;
}

}  // namespace sheetmesh
