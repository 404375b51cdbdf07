// The report's part of the voxel layer (thickness, grey levels, sheetness): the `Fields()`
// its results declare, with the report's JSON names (run/pipeline_report.cc nests them).
#include <nlohmann/json.hpp>

#include "worker/pipeline/voxel/grey_volume.h"
#include "worker/pipeline/voxel/sheetness.h"
#include "worker/pipeline/voxel/thickness.h"

namespace sheetmesh {

nlohmann::json ThicknessStats::Fields() const {
  return {{"mean", mean}, {"median", median}, {"min", min}, {"max", max}};
}

nlohmann::json GreyLevels::Fields() const {
  nlohmann::json j = {{"rock", rock},
                      {"void", void_level},
                      {"noise", noise},
                      {"contrast_to_noise", cnr()},
                      {"rock_measured", rock_measured},
                      {"void_measured", void_measured}};
  if (!problem.empty()) j["problem"] = problem;
  return j;
}

nlohmann::json SheetnessStats::Fields() const {
  return {{"noise_per_scale", noise},     {"seeds", seeds},
          {"detected_voxels", detected},  {"slabs", slabs},
          {"noise_slices", noise_slices}, {"seconds", seconds}};
}

}  // namespace sheetmesh
