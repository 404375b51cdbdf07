// The report's part of the extraction and the pieces: the `Fields()` its results declare, with the
// report's JSON names (run/pipeline_report.cc nests them).
#include <nlohmann/json.hpp>

#include "worker/pipeline/extract/extraction.h"
#include "worker/pipeline/extract/piece_geology.h"

namespace sheetmesh {

nlohmann::json ExtractionStep::Fields() const {
  return {{"step", name},
          {"ran", ran},
          {"voxels_before", voxels_before},
          {"voxels_after", voxels_after},
          {"added", added},
          {"removed", removed},
          {"objects_before", objects_before},
          {"objects_after", objects_after},
          {"rounds", rounds},
          {"seconds", seconds}};
}

nlohmann::json ExtractionRetention::Fields() const {
  return {{"input_voxels", input_voxels},
          {"kept", kept},
          {"fraction_kept", fraction_kept()},
          {"dropped_by_refine", dropped_by_refine},
          {"dropped_specks", dropped_specks},
          {"dropped_at_crossings", dropped_at_crossings},
          {"dropped_minor_pieces", dropped_minor_pieces},
          {"kept_per_piece", kept_per_piece}};
}

nlohmann::json ExtractionSummary::Fields() const {
  nlohmann::json s = nlohmann::json::array();
  for (const ExtractionStep& step : steps) s.push_back(step.Fields());
  nlohmann::json used = nlohmann::json::object();
  for (const DerivedValue& d : derived) used[d.key] = {{"value", d.value}, {"from", d.from}};
  return {{"steps", s},
          {"scale", used},
          {"retention", retention.Fields()},
          {"min_object_voxels", min_object_voxels},
          {"model_voxels", model_voxels},
          {"pieces", pieces}};
}

nlohmann::json PieceGeology::Fields() const {
  return {{"piece", piece},
          {"sheet", sheet},
          {"voxels", voxels},
          {"triangles", triangles},
          {"area", area},
          {"mean_aperture", mean_aperture},
          {"max_aperture", max_aperture},
          {"normal", {normal.x, normal.y, normal.z}},
          {"dip_degrees", dip_degrees},
          {"dip_direction_degrees", dip_direction_degrees},
          {"planarity", planarity},
          {"centroid", {centroid.x, centroid.y, centroid.z}}};
}

}  // namespace sheetmesh
