// The legends drawn below the previews: lines of text, each with a colour swatch or none.
#ifndef SHEETMESH_WORKER_PIPELINE_PREVIEW_LEGEND_H_
#define SHEETMESH_WORKER_PIPELINE_PREVIEW_LEGEND_H_

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "worker/pipeline/preview/rgb_image.h"

namespace sheetmesh {

// One line of a legend: a swatch of `swatch` (unless it is unset) and its text.
struct LegendLine {
  std::optional<std::array<uint8_t, 3>> swatch;
  std::string text;
};

// Adds the legend `lines` below `im` on `background` in `ink`, widening the picture (with
// `background`) where a line needs it.
void AppendLegend(RgbImage* im, const std::vector<LegendLine>& lines,
                  const std::array<uint8_t, 3>& background, const std::array<uint8_t, 3>& ink);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_PREVIEW_LEGEND_H_
