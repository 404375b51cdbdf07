// PipelineReport::ToJson: the report artifact. Each stage's result lists its own fields;
// this only nests them.
#include <algorithm>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "absl/strings/str_format.h"
#include "common/json_text.h"
#include "common/version.h"
#include "worker/pipeline/run/parameters_json.h"
#include "worker/pipeline/run/pipeline.h"

namespace sheetmesh {
namespace {

nlohmann::json Vec(const Vec3& v) { return {v.x, v.y, v.z}; }

// The grid model that scores lowest (the floor), or none.
const GridFigure* Floor(const std::vector<GridFigure>& grid) {
  if (grid.empty()) return nullptr;
  return &*std::min_element(grid.begin(), grid.end(), [](const GridFigure& a, const GridFigure& b) {
    return a.similarity < b.similarity;
  });
}

}  // namespace

std::optional<std::string> SimilarityReport::FloorWarning() const {
  const GridFigure* floor_model = Floor(grid);
  if (floor_model == nullptr || !(score.similarity < floor_model->similarity)) return std::nullopt;
  const GridFigure& floor = *floor_model;
  return absl::StrFormat(
      "similarity %.4f is under the grid model's %.4f (every %d%s voxel kept, %d cells: the "
      "paper's Table 2 floor); a finer budget (a smaller r, more triangles) or "
      "surface.representation = auto or body for thick pieces scores higher",
      score.similarity, floor.similarity, floor.rate,
      floor.rate == 2   ? "nd"
      : floor.rate == 3 ? "rd"
                        : "th",
      floor.grid_quantity);
}

nlohmann::json SimilarityReport::Fields() const {
  nlohmann::json j = score.Fields();
  j["against"] = against_model ? "extracted model" : "input sheet phase";
  j["shell_similarity"] = shell_similarity;
  nlohmann::json g = nlohmann::json::array();
  for (const GridFigure& f : grid) {
    g.push_back(
        {{"rate", f.rate}, {"similarity", f.similarity}, {"grid_quantity", f.grid_quantity}});
  }
  j["grid_models"] = g;
  if (const std::optional<std::string> w = FloorWarning()) {
    const GridFigure& floor = *Floor(grid);
    j["floor_warning"] = {{"text", *w},
                          {"similarity", score.similarity},
                          {"floor", floor.similarity},
                          {"rate", floor.rate}};
  }
  if (raw) {
    j["raw"] = raw->Fields();
    j["raw"]["against"] = "input sheet phase";
  }
  return j;
}

std::string PipelineReport::ToJson() const {
  const Placement& pl = volume.placement;
  nlohmann::json j;
  j["sheetmesh_version"] = SHEETMESH_VERSION;
  j["input"] = {{"path", volume.path},
                {"format", volume.format},
                {"dims", {volume.dims.nx, volume.dims.ny, volume.dims.nz}},
                {"dtype", std::string(DTypeName(volume.dtype))},
                {"spacing", Vec(pl.spacing)},
                {"origin", Vec(pl.origin)},
                {"unit", pl.unit},
                {"selection", options.input.threshold.empty() ? options.input.selection.ToString()
                                                              : selection.ToString()}};
  if (threshold) {
    j["input"]["threshold"] = {{"value", *threshold},
                               {"method", options.input.threshold == "otsu" ? "otsu" : "given"},
                               {"phase", options.input.threshold_above ? "above" : "below"}};
  }
  if (sheet_voxels > 0) {
    j["input"]["sheet_voxels"] = sheet_voxels;
    j["input"]["components"] = components;
    j["input"]["thickness_voxels"] = thickness.Fields();
  }
  j["parameters"] = ParametersJson(options, /*include_local=*/true);
  if (extraction) {
    j["extraction"] = extraction->Fields();
    nlohmann::json pieces = nlohmann::json::array();
    int32_t sheets = 0;
    for (const PieceGeology& g : geology) {
      pieces.push_back(g.Fields());
      sheets = std::max(sheets, g.sheet + 1);
    }
    j["pieces"] = pieces;
    j["extraction"]["sheets"] = sheets;
  }
  if (surface) j["surface"] = surface->Fields();
  if (representation) j["representation"] = representation->Fields();
  if (similarity) j["similarity"] = similarity->Fields();
  if (radius_choice) {
    j["radius_search"] = radius_choice->Fields();
    j["radius_search"]["goal"] =
        options.radius_search.goal == RadiusGoal::kBestSimilarity ? "best" : "target";
    j["radius_search"]["target_similarity"] = options.radius_search.target_similarity;
  }
  if (volume_mesh) j["volume_mesh"] = volume_mesh->Fields();
  if (volume_split) j["volume_split"] = volume_split->Fields();
  if (flow) {
    j["flow"] = flow->Fields();
    if (flow_image) j["flow"]["image_reference"] = flow_image->Fields();
    if (!flow_image_skipped.empty()) {
      j["flow"]["image_reference"] = {{"skipped", flow_image_skipped}};
    }
  }
  if (sheetness) {
    j["grey"] = {{"sheetness", sheetness->Fields()}};
    if (grey_apertures) {
      const nlohmann::json a = grey_apertures->Fields();
      for (auto it = a.begin(); it != a.end(); ++it) j["grey"][it.key()] = it.value();
    }
  }
  if (!failed_stage.empty()) j["failed"] = {{"stage", failed_stage}, {"error", error}};
  nlohmann::json times = nlohmann::json::object();
  for (const StageTime& t : timings) times[t.stage] = t.seconds;
  j["seconds"] = times;
  if (!previews.empty()) {
    nlohmann::json list = nlohmann::json::array();
    for (const std::string& p : previews) list.push_back(nlohmann::json::parse(p));
    j["previews"] = list;
  }
  j["files"] = files;
  if (!not_written.empty()) {
    nlohmann::json skipped = nlohmann::json::array();
    for (const auto& [name, why] : not_written) skipped.push_back({{"file", name}, {"why", why}});
    j["not_written"] = skipped;
  }
  return JsonText(j, 2);
}

}  // namespace sheetmesh
