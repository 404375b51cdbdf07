// The report's part of the dual triangles: the `Fields()` its results declare, with the
// report's JSON names (run/pipeline_report.cc nests them).
#include <nlohmann/json.hpp>

#include "worker/pipeline/scvd/dual_triangles.h"

namespace sheetmesh {

nlohmann::json DualTriangleStats::Fields() const {
  return {{"candidates", candidates},
          {"blocks_three_cells", blocks_three},
          {"blocks_amended", blocks_amended},
          {"blocks_unresolved", blocks_unresolved},
          {"kept", kept},
          {"rejected_fold", rejected_fold},
          {"rejected_intersection", rejected_intersection},
          {"rejected_degenerate", rejected_degenerate},
          {"rim_vertices", rim_vertices},
          {"rim_triangles", rim_faces},
          {"crack_triangles", crack_faces}};
}

}  // namespace sheetmesh
