#include "worker/pipeline/cli/info_command.h"

#include <nlohmann/json.hpp>

#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "common/json_text.h"
#include "common/status_macros.h"
#include "worker/pipeline/voxel/thickness.h"

namespace sheetmesh {

absl::Status RunInfo(const InfoOptions& options, std::ostream& out) {
  SM_ASSIGN_OR_RETURN(SheetPhase phase, LoadSheetPhase(options.input));
  absl::Time t0 = absl::Now();
  SM_ASSIGN_OR_RETURN(std::vector<uint16_t> tau, ComputeThickness(phase.sheet));
  const ThicknessStats ts = SummarizeThickness(tau);
  const double thickness_s = absl::ToDoubleSeconds(absl::Now() - t0);
  t0 = absl::Now();
  SM_ASSIGN_OR_RETURN(Components comps, LabelComponents(phase.sheet, options.connectivity));
  const double components_s = absl::ToDoubleSeconds(absl::Now() - t0);

  const VolumeInfo& info = phase.info;
  const Placement& p = info.placement;
  const double fraction = double(phase.sheet.size()) / info.dims.num_voxels();
  std::vector<uint64_t> largest(
      comps.sizes.begin(),
      comps.sizes.begin() + std::min<size_t>(comps.sizes.size(), options.largest_components));
  uint64_t singletons = 0;
  for (uint64_t s : comps.sizes) singletons += s == 1;

  if (options.json) {
    nlohmann::json j;
    j["path"] = info.path;
    j["format"] = info.format;
    j["dims"] = {info.dims.nx, info.dims.ny, info.dims.nz};
    j["dtype"] = std::string(DTypeName(info.dtype));
    j["spacing"] = {p.spacing.x, p.spacing.y, p.spacing.z};
    j["origin"] = {p.origin.x, p.origin.y, p.origin.z};
    j["unit"] = p.unit;
    j["value_range"] = {phase.stats.min_value, phase.stats.max_value};
    j["selection"] = phase.selection.ToString();
    if (phase.threshold) {
      j["threshold"] = {{"value", *phase.threshold},
                        {"method", options.input.threshold == "otsu" ? "otsu" : "given"},
                        {"phase", options.input.threshold_above ? "above" : "below"}};
    }
    j["sheet_voxels"] = phase.sheet.size();
    j["sheet_fraction"] = fraction;
    if (phase.mask) j["mask_voxels"] = phase.mask->size();
    j["thickness"] = {{"mean", ts.mean},
                      {"min", ts.min},
                      {"max", ts.max},
                      {"median", ts.median},
                      {"histogram", ts.histogram}};
    j["components"] = {{"connectivity", static_cast<int>(options.connectivity)},
                       {"count", comps.count()},
                       {"single_voxel", singletons},
                       {"largest", largest}};
    j["memory_bytes"] = {{"sheet_set", phase.sheet.MemoryBytes()},
                         {"thickness", tau.size() * sizeof(uint16_t)}};
    j["seconds"] = {{"read_and_select", phase.read_seconds},
                    {"thickness", thickness_s},
                    {"components", components_s}};
    out << JsonText(j, 2) << "\n";
    return absl::OkStatus();
  }
  out << absl::StrFormat("volume      %s (%s)\n", info.path, info.format);
  out << absl::StrFormat("dims        %d x %d x %d %s (%d voxels)\n", info.dims.nx, info.dims.ny,
                         info.dims.nz, DTypeName(info.dtype), info.dims.num_voxels());
  out << absl::StrFormat("spacing     %g %g %g %s, origin %g %g %g\n", p.spacing.x, p.spacing.y,
                         p.spacing.z, p.unit.empty() ? "(unit unknown)" : p.unit, p.origin.x,
                         p.origin.y, p.origin.z);
  out << absl::StrFormat("values      %g .. %g\n", phase.stats.min_value, phase.stats.max_value);
  const std::string selected =
      phase.threshold
          ? absl::StrFormat("%s %s threshold %g",
                            options.input.threshold_above ? "at or above the" : "below the",
                            options.input.threshold == "otsu" ? "Otsu" : "given", *phase.threshold)
          : phase.selection.ToString();
  out << absl::StrFormat("sheet       %s: %d voxels (%.3f%% of the box)\n", selected,
                         phase.sheet.size(), 100 * fraction);
  if (phase.mask) out << absl::StrFormat("rock mask   %d voxels\n", phase.mask->size());
  out << absl::StrFormat("thickness   mean %.3f, median %g, min %d, max %d voxels\n", ts.mean,
                         ts.median, ts.min, ts.max);
  out << absl::StrFormat("components  %d under %d-connectivity (%d single voxels); largest:",
                         comps.count(), static_cast<int>(options.connectivity), singletons);
  for (uint64_t s : largest) out << " " << s;
  out << "\n";
  out << absl::StrFormat("time        read+select %.2f s, thickness %.2f s, components %.2f s\n",
                         phase.read_seconds, thickness_s, components_s);
  return absl::OkStatus();
}

}  // namespace sheetmesh
