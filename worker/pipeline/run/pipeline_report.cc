// PipelineReport::ToJson: the report artifact.
#include <nlohmann/json.hpp>

#include "common/json_text.h"
#include "common/version.h"
#include "worker/pipeline/mesh/mesh_io.h"
#include "worker/pipeline/run/pipeline.h"

namespace sheetmesh {
namespace {

nlohmann::json Vec(const Vec3& v) { return {v.x, v.y, v.z}; }

const char* PlacementName(VertexPlacement p) {
  return p == VertexPlacement::kCentroid ? "centroid" : "generator";
}
const char* MeasureName(ThicknessMeasure m) {
  return m == ThicknessMeasure::kNormal ? "normal" : "axis_runs";
}
const char* HeightName(PrismHeight h) { return h == PrismHeight::kVertex ? "vertex" : "face"; }

}  // namespace

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
                {"selection", options.input.selection.ToString()},
                {"sheet_voxels", sheet_voxels},
                {"components", components},
                {"thickness_voxels",
                 {{"mean", thickness.mean},
                  {"median", thickness.median},
                  {"min", thickness.min},
                  {"max", thickness.max}}}};
  const SurfaceOptions& s = options.surface;
  j["parameters"] = {{"r", s.scvd.radius_voxels},
                     {"seed", s.scvd.seed},
                     {"generator_count", s.scvd.generator_count},
                     {"mean_thickness", s.scvd.mean_thickness_voxels},
                     {"lloyd_max_iter", s.scvd.lloyd_max_iter},
                     {"lloyd_tol", s.scvd.lloyd_tol},
                     {"fold_angle_degrees", s.triangles.fold_angle_degrees},
                     {"rim", s.triangles.rim},
                     {"vertex_placement", PlacementName(s.placement)},
                     {"thickness_measure", MeasureName(s.thickness)},
                     {"similarity_model", HeightName(options.score.height)}};
  j["scvd"] = {{"generators", generators},
               {"lloyd_iterations", lloyd_iterations},
               {"lloyd_converged", lloyd_converged},
               {"energy", energy}};
  j["surface"] = {{"vertices", vertices},
                  {"triangles", triangles},
                  {"element_size_voxels", element_size_voxels},
                  {"element_size", PhysicalLength(element_size_voxels, pl)},
                  {"area_voxels", area_voxels},
                  {"candidates", triangle_stats.candidates},
                  {"blocks_three_cells", triangle_stats.blocks_three},
                  {"blocks_amended", triangle_stats.blocks_amended},
                  {"rejected_fold", triangle_stats.rejected_fold},
                  {"rejected_intersection", triangle_stats.rejected_intersection},
                  {"rejected_degenerate", triangle_stats.rejected_degenerate},
                  {"rim_vertices", triangle_stats.rim_vertices},
                  {"rim_triangles", triangle_stats.rim_faces},
                  {"crack_triangles", triangle_stats.crack_faces},
                  {"components_without_triangles", skipped_components},
                  {"voxels_without_triangles", skipped_voxels},
                  {"topology",
                   {{"edges", topology.edges},
                    {"boundary_edges", topology.boundary_edges},
                    {"nonmanifold_edges", topology.nonmanifold_edges},
                    {"boundary_loops", topology.boundary_loops},
                    {"pieces", topology.pieces},
                    {"inconsistent_edges", topology.inconsistent_edges},
                    {"duplicate_faces", topology.duplicate_faces},
                    {"degenerate_faces", topology.degenerate_faces}}}};
  nlohmann::json sim = {{"against", "input sheet phase"},
                        {"similarity", similarity.similarity},
                        {"c_in", similarity.c_in},
                        {"c_out", similarity.c_out},
                        {"c_image", similarity.c_image},
                        {"dice", similarity.dice},
                        {"shell_similarity", shell_similarity}};
  if (similarity.hausdorff >= 0) sim["hausdorff_voxels"] = similarity.hausdorff;
  nlohmann::json grid_json = nlohmann::json::array();
  for (const GridFigure& g : grid) {
    grid_json.push_back(
        {{"rate", g.rate}, {"similarity", g.similarity}, {"grid_quantity", g.grid_quantity}});
  }
  sim["grid_models"] = grid_json;
  if (options.extract) {
    sim["against"] = "extracted model";
    sim["raw"] = {{"against", "input sheet phase"},    {"similarity", similarity_raw.similarity},
                  {"c_in", similarity_raw.c_in},       {"c_out", similarity_raw.c_out},
                  {"c_image", similarity_raw.c_image}, {"dice", similarity_raw.dice}};
    const ExtractionOptions& e = options.extraction;
    nlohmann::json steps = nlohmann::json::array();
    for (const ExtractionStep& s : extraction_steps) {
      steps.push_back({{"step", s.name},
                       {"ran", s.ran},
                       {"voxels_before", s.voxels_before},
                       {"voxels_after", s.voxels_after},
                       {"added", s.added},
                       {"removed", s.removed},
                       {"objects_before", s.objects_before},
                       {"objects_after", s.objects_after},
                       {"seconds", s.seconds}});
    }
    j["extraction"] = {{"parameters",
                        {{"refine", e.refine},
                         {"refine_close_radius", e.refine_close_radius},
                         {"refine_open_radius", e.refine_open_radius},
                         {"detect", e.detect},
                         {"detect_t", e.detect_extend.half_thickness_voxels},
                         {"detect_R", e.detect_extend.radius_voxels},
                         {"detect_rounds", e.detect_extend.max_rounds},
                         {"M", min_object_voxels},
                         {"separate", e.separate},
                         {"separate_r", e.separation.radius_voxels},
                         {"D_ang", e.separation.dihedral_degrees},
                         {"remove_minor", e.remove_minor},
                         {"recover", e.recover},
                         {"recover_t", e.recover_extend.half_thickness_voxels},
                         {"recover_R", e.recover_extend.radius_voxels},
                         {"recover_rounds", e.recover_extend.max_rounds}}},
                       {"steps", steps},
                       {"model_voxels", model_voxels},
                       {"pieces", pieces}};
    nlohmann::json geo = nlohmann::json::array();
    for (const PieceGeology& g : geology) {
      geo.push_back({{"piece", g.piece},
                     {"voxels", g.voxels},
                     {"triangles", g.triangles},
                     {"area", g.area},
                     {"mean_aperture", g.mean_aperture},
                     {"max_aperture", g.max_aperture},
                     {"normal", Vec(g.normal)},
                     {"dip_degrees", g.dip_degrees},
                     {"dip_direction_degrees", g.dip_direction_degrees},
                     {"planarity", g.planarity},
                     {"centroid", Vec(g.centroid)}});
    }
    j["pieces"] = geo;
  }
  j["similarity"] = sim;
  if (options.search_radius) {
    nlohmann::json trials = nlohmann::json::array();
    for (const RadiusTrial& t : radius_choice.trials) {
      trials.push_back({{"r", t.radius}, {"triangles", t.triangles}, {"similarity", t.similarity}});
    }
    j["radius_search"] = {
        {"goal", options.radius_search.goal == RadiusGoal::kBestSimilarity ? "best" : "target"},
        {"target_similarity", options.radius_search.target_similarity},
        {"chosen_r", radius_choice.radius},
        {"target_reached", radius_choice.target_reached},
        {"trials", trials}};
  }
  if (has_volume_mesh) {
    auto stat = [](const QualityStat& q) {
      return nlohmann::json{{"min", q.min},
                            {"mean", q.mean},
                            {"histogram_range", {q.lo, q.hi}},
                            {"histogram", q.histogram}};
    };
    const TetgenOptions& tg = options.volume.tetgen;
    j["volume_mesh"] = {{"parameters",
                         {{"max_radius_edge_ratio", tg.max_radius_edge_ratio},
                          {"min_dihedral_degrees", tg.min_dihedral_degrees},
                          {"max_volume", tg.max_volume},
                          {"steiner_on_sheets", tg.steiner_on_sheets},
                          {"tetgen_switches", TetgenSwitches(tg)},
                          {"repair", options.volume.plc.repair}}},
                        {"nodes", volume_nodes},
                        {"tetrahedra", volume_tets},
                        {"sheet_faces", volume_sheet_faces},
                        {"voxels_per_tetrahedron", voxels_per_tet},
                        {"volume", volume_quality.volume},
                        {"snapped_vertices", volume_snapped},
                        {"snap_held_vertices", volume_snap_held},
                        {"repaired_triangles", volume_repaired},
                        {"flipped_edges", volume_flipped},
                        {"dropped_caps", volume_dropped_caps},
                        {"dropped_overlaps", volume_dropped_overlaps},
                        {"closed_slits", volume_closed_slits},
                        {"opened_wedges", volume_opened_wedges},
                        {"box_points", volume_box_points},
                        {"seed_points", volume_seed_points},
                        {"rederived_facets", volume_rederived_facets},
                        {"conformity",
                         {{"sheet_triangles", volume_conformity.sheet_triangles},
                          {"conforming", volume_conformity.conforming},
                          {"worst_area_error", volume_conformity.worst_area_error}}},
                        {"quality",
                         {{"min_dihedral_degrees", stat(volume_quality.min_dihedral)},
                          {"gamma", stat(volume_quality.gamma)},
                          {"edge_aspect", stat(volume_quality.edge_aspect)},
                          {"radius_aspect", stat(volume_quality.radius_aspect)}}}};
    for (const auto& [name, value] : volume_improvement.Fields()) {
      j["volume_mesh"]["improvement"][name] = value;
    }
  }
  nlohmann::json times = nlohmann::json::object();
  for (const StageTime& t : timings) times[t.stage] = t.seconds;
  j["seconds"] = times;
  j["files"] = files;
  return JsonText(j, 2);
}

}  // namespace sheetmesh
