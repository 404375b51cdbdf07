#include "worker/pipeline/voxel/sheet_input.h"

#include "absl/time/clock.h"
#include "common/status_macros.h"

namespace sheetmesh {

absl::StatusOr<SheetPhase> LoadSheetPhase(const SheetInput& input, const Progress& progress) {
  const absl::Time start = absl::Now();
  SheetPhase out;
  const bool has_mask = !input.mask_path.empty() || input.mask_from_volume;
  if (has_mask) {
    const std::string& mpath = input.mask_from_volume ? input.path : input.mask_path;
    SM_ASSIGN_OR_RETURN(auto msource, OpenVolume(mpath, input.open));
    SelectionStats mstats;
    SM_ASSIGN_OR_RETURN(VoxelSet mask, SelectPhase(*msource, input.mask_selection, nullptr,
                                                   &mstats, progress.Sub(0, 0.5)));
    SM_RETURN_IF_ERROR(CheckNotEmpty(mask, msource->info(), input.mask_selection, mstats));
    out.mask = std::move(mask);
  }
  SM_ASSIGN_OR_RETURN(auto source, OpenVolume(input.path, input.open));
  out.info = source->info();
  SM_ASSIGN_OR_RETURN(out.sheet,
                      SelectPhase(*source, input.selection, out.mask ? &*out.mask : nullptr,
                                  &out.stats, has_mask ? progress.Sub(0.5, 1) : progress));
  SM_RETURN_IF_ERROR(CheckNotEmpty(out.sheet, out.info, input.selection, out.stats));
  out.read_seconds = absl::ToDoubleSeconds(absl::Now() - start);
  return out;
}

}  // namespace sheetmesh
