// The report's part of the similarity: the `Fields()` its results declare, with the
// report's JSON names (run/pipeline_report.cc nests them).
#include <nlohmann/json.hpp>

#include "worker/pipeline/similarity/similarity.h"

namespace sheetmesh {

nlohmann::json SimilarityScore::Fields() const {
  nlohmann::json j = {{"similarity", similarity},
                      {"c_in", c_in},
                      {"c_out", c_out},
                      {"c_image", c_image},
                      {"dice", dice}};
  if (hausdorff >= 0) j["hausdorff_voxels"] = hausdorff;
  return j;
}

}  // namespace sheetmesh
