// The report's part of the surface, the radius search and the representations: the
// `Fields()` their results declare, with the report's JSON names (run/pipeline_report.cc
// nests them).
#include <nlohmann/json.hpp>

#include "worker/pipeline/surface/grey_apertures.h"
#include "worker/pipeline/surface/radius_search.h"
#include "worker/pipeline/surface/representation.h"
#include "worker/pipeline/surface/surface_builder.h"

namespace sheetmesh {

nlohmann::json SurfaceStats::Fields() const {
  nlohmann::json j = triangle_stats.Fields();
  j["vertices"] = vertices;
  j["triangles"] = triangles;
  j["element_size_voxels"] = element_size_voxels;
  j["element_size"] = element_size;
  j["area_voxels"] = area_voxels;
  j["components_without_triangles"] = skipped_components;
  j["voxels_without_triangles"] = skipped_voxels;
  j["topology"] = topology.Fields();
  j["smoothed_vertices"] = smoothed_vertices;
  if (error_density) {
    j["error_density"] = {{"plain_similarity", error_density->plain_similarity},
                          {"weighted_similarity", error_density->weighted_similarity},
                          {"kept_weighted", error_density->kept_weighted}};
  }
  if (mesher_choice) {
    j["mesher_choice"] = {{"scvd_similarity", mesher_choice->scvd_similarity},
                          {"midsurface_similarity", mesher_choice->mid_similarity},
                          {"kept", mesher_choice->kept_mid ? "midsurface" : "scvd"},
                          {"margin", mesher_choice->margin}};
  }
  if (decimation) {
    j["decimation"] = {{"dual_triangles", decimation->faces_before},
                       {"collapses", decimation->collapses},
                       {"largest_error_voxels2", decimation->largest_error}};
  }
  if (apertures) {
    j["apertures"] = {{"covered_faces_given_their_sheets", apertures->covered},
                      {"hole_faces", apertures->holes},
                      {"junction_faces", apertures->junction},
                      {"junction_faces_lowered", apertures->junction_lowered},
                      {"junction_faces_raised", apertures->junction_raised}};
  }
  if (vertex_fit) {
    j["vertex_fit"] = {{"vertices_tried", vertex_fit->vertices_tried},
                       {"moves", vertex_fit->moves},
                       {"voxels_gained", vertex_fit->voxels_gained}};
  }
  j["scvd"] = {{"generators", generators},
               {"lloyd_iterations", lloyd_iterations},
               {"lloyd_converged", lloyd_converged},
               {"energy", energy}};
  if (bricks > 0) {
    j["bricks"] = {
        {"bricks", bricks}, {"halo_voxels", brick_halo}, {"seam_mismatches", seam_mismatches}};
  }
  return j;
}

nlohmann::json RadiusChoice::Fields() const {
  nlohmann::json t = nlohmann::json::array();
  for (const RadiusTrial& x : trials) {
    nlohmann::json trial = {{"r", x.radius}, {"triangles", x.triangles}};
    if (x.scored) trial["similarity"] = x.similarity;
    if (x.decimated_to > 0) trial["decimated_to"] = x.decimated_to;
    t.push_back(std::move(trial));
  }
  nlohmann::json j = {{"chosen_r", radius}, {"target_reached", target_reached}, {"trials", t}};
  if (decimated_to > 0) j["decimated_to"] = decimated_to;
  if (!message.empty()) j["message"] = message;
  return j;
}

nlohmann::json PieceRepresentation::Fields() const {
  nlohmann::json j = {{"piece", piece},
                      {"part_of", part_of},
                      {"representation", body ? "body" : "sheet"},
                      {"voxels", voxels},
                      {"thickness_voxels", thickness},
                      {"median_thickness_voxels", median_thickness},
                      {"sheet_triangles", sheet_triangles},
                      {"reason", reason}};
  if (sheet_similarity) j["sheet_similarity"] = *sheet_similarity;
  if (body) j["equivalent_aperture_voxels"] = equivalent_aperture;
  if (body_similarity) {
    j["body_similarity"] = *body_similarity;
    j["body_triangles"] = body_triangles;
    j["body_triangles_before_decimation"] = body_triangles_before;
  }
  return j;
}

nlohmann::json RepresentationReport::Fields() const {
  nlohmann::json j = {{"mode", RepresentationName(mode)}, {"bodies", bodies}};
  j["pieces"] = nlohmann::json::array();
  for (const PieceRepresentation& p : pieces) j["pieces"].push_back(p.Fields());
  return j;
}

nlohmann::json GreyApertureStats::Fields() const {
  nlohmann::json j = {{"levels", levels.Fields()}, {"measured", measured}};
  if (measured) {
    j["faces"] = faces;
    j["mean_aperture_voxels"] = mean_voxels;
    j["counted_mean_aperture_voxels"] = counted_mean_voxels;
    j["uncertainty_voxels"] = uncertainty_voxels;
    j["window_voxels"] = window_voxels;
  } else {
    j["fallback"] = "apertures counted from voxels: " + levels.problem;
  }
  return j;
}

}  // namespace sheetmesh
