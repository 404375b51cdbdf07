// The report's part of the mesh topology: the `Fields()` its results declare, with the
// report's JSON names (run/pipeline_report.cc nests them).
#include <nlohmann/json.hpp>

#include "worker/pipeline/mesh/mesh_topology.h"

namespace sheetmesh {

nlohmann::json TopologyReport::Fields() const {
  return {{"edges", edges},
          {"boundary_edges", boundary_edges},
          {"nonmanifold_edges", nonmanifold_edges},
          {"boundary_loops", boundary_loops},
          {"connected_parts", connected_parts},
          {"inconsistent_edges", inconsistent_edges},
          {"duplicate_faces", duplicate_faces},
          {"degenerate_faces", degenerate_faces},
          {"unused_vertices", unused_vertices}};
}

}  // namespace sheetmesh
