// The report's part of the thickness: the `Fields()` its results declare, with the
// report's JSON names (run/pipeline_report.cc nests them).
#include <nlohmann/json.hpp>

#include "worker/pipeline/voxel/thickness.h"

namespace sheetmesh {

nlohmann::json ThicknessStats::Fields() const {
  return {{"mean", mean}, {"median", median}, {"min", min}, {"max", max}};
}

}  // namespace sheetmesh
