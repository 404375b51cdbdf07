// Every stage's part of the report (the `Fields()` its result struct declares), in one
// translation unit: one file knows the report's JSON names, and nlohmann's header, heavy to
// compile, is compiled once for them all instead of once per stage.
#include <nlohmann/json.hpp>

#include "worker/pipeline/extract/extraction.h"
#include "worker/pipeline/extract/piece_geology.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/scvd/dual_triangles.h"
#include "worker/pipeline/similarity/similarity.h"
#include "worker/pipeline/surface/radius_search.h"
#include "worker/pipeline/surface/surface_builder.h"
#include "worker/pipeline/tet/plc.h"
#include "worker/pipeline/tet/tet_improve.h"
#include "worker/pipeline/tet/tet_quality.h"
#include "worker/pipeline/tet/volume_mesher.h"
#include "worker/pipeline/voxel/thickness.h"

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

nlohmann::json ThicknessStats::Fields() const {
  return {{"mean", mean}, {"median", median}, {"min", min}, {"max", max}};
}

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

nlohmann::json SimilarityScore::Fields() const {
  nlohmann::json j = {{"similarity", similarity},
                      {"c_in", c_in},
                      {"c_out", c_out},
                      {"c_image", c_image},
                      {"dice", dice}};
  if (hausdorff >= 0) j["hausdorff_voxels"] = hausdorff;
  return j;
}

nlohmann::json QualityStat::Fields() const {
  return {{"min", min}, {"mean", mean}, {"histogram_range", {lo, hi}}, {"histogram", histogram}};
}

nlohmann::json TetQuality::Fields() const {
  return {{"min_dihedral_degrees", min_dihedral.Fields()},
          {"gamma", gamma.Fields()},
          {"edge_aspect", edge_aspect.Fields()},
          {"radius_aspect", radius_aspect.Fields()}};
}

nlohmann::json TetImproveReport::Fields() const {
  return {{"passes", passes},
          {"edge_removals", edge_removals},
          {"face_removals", face_removals},
          {"smoothing_moves", smoothing_moves},
          {"inserted_vertices", inserted_vertices},
          {"sheet_face_splits", sheet_face_splits},
          {"sheet_edge_splits", sheet_edge_splits},
          {"over_budget", over_budget},
          {"retries_skipped", retries_skipped},
          {"movable_vertices", movable_vertices},
          {"sliding_vertices", sliding_vertices},
          {"min_dihedral_before", min_dihedral_before},
          {"mean_dihedral_before", mean_dihedral_before},
          {"min_dihedral_after", min_dihedral_after},
          {"mean_dihedral_after", mean_dihedral_after},
          {"seconds", seconds}};
}

nlohmann::json PlcStats::Fields() const {
  nlohmann::json places = nlohmann::json::array();
  for (const Vec3& p : contact_places) places.push_back({p.x, p.y, p.z});
  return {{"snapped_vertices", snapped_vertices},
          {"snap_held_vertices", snap_held_vertices},
          {"merged_vertices", merged_vertices},
          {"dropped_triangles", dropped_triangles},
          {"repaired_triangles", repaired_triangles},
          {"repaired_area_voxels", repaired_area_voxels},
          {"untangled",
           {{"clashing_pairs", clashing_pairs},
            {"moved_vertices", untangle_moves},
            {"flipped_edges", untangle_flips},
            {"split_crossings", untangle_splits},
            {"thin_splits", untangle_thin_splits},
            {"retriangulated_patches", untangle_patches},
            {"max_move_voxels", untangle_max_move}}},
          {"flipped_edges", flipped_edges},
          {"dropped_caps", dropped_caps},
          {"dropped_overlaps", dropped_overlaps},
          {"closed_slits", closed_slits},
          {"opened_wedges", opened_wedges},
          {"collapsed_edges", collapsed_edges},
          {"mended_contacts", mended_contacts},
          {"unmended_contacts", unmended_contacts},
          {"joined_touches", joined_touches},
          {"contact_places", places},
          {"box_points", box_points},
          {"seed_points", seed_points},
          {"lattice_spacing", lattice_spacing}};
}

nlohmann::json Conformity::Fields() const {
  return {{"sheet_triangles", sheet_triangles},
          {"conforming", conforming},
          {"worst_area_error", worst_area_error}};
}

nlohmann::json VolumeMeshStats::Fields() const {
  nlohmann::json j = PlcStats::Fields();
  j["nodes"] = nodes;
  j["tetrahedra"] = tetrahedra;
  j["sheet_faces"] = sheet_faces;
  if (!bodies.empty()) {
    nlohmann::json list = nlohmann::json::array();
    for (const BodyRegion& b : bodies) {
      list.push_back({{"piece", b.piece}, {"tetrahedra", b.tetrahedra}, {"volume", b.volume}});
    }
    j["bodies"] = list;
  }
  if (delivered_similarity) j["similarity_of_its_sheets"] = *delivered_similarity;
  j["voxels_per_tetrahedron"] = voxels_per_tet;
  j["volume"] = quality.volume;
  j["tetgen_switches"] = tetgen_switches;
  j["tetgen_seconds"] = tetgen_seconds;
  j["tetgen_tetrahedra"] = tetgen_tetrahedra;
  j["tetgen_recovery"] = tetgen_recovery;
  // The sizing used: the lattice (in median sheet edges and physical units, finest and
  // coarsest level), its grading, and the budget with the TetGen runs it took.
  j["sizing"] = {{"lattice", lattice},
                 {"grading", grading},
                 {"finest_spacing", lattice_spacing},
                 {"coarsest_spacing", lattice_coarsest},
                 {"levels", lattice_levels},
                 {"max_tetrahedra", max_tetrahedra},
                 {"predicted_tetrahedra", predicted_tetrahedra},
                 {"predictions", sizing_predictions},
                 {"attempts", sizing_attempts}};
  j["rederived_facets"] = rederived_facets;
  j["conformity"] = conformity.Fields();
  j["quality"] = quality.Fields();
  j["improvement"] = improvement.Fields();
  j["sliver_refinement"] = {{"min_dihedral_before", sliver_refinement.min_dihedral_before},
                            {"slivers_on_sheets", sliver_refinement.slivers_on_sheets},
                            {"rounds", sliver_refinement.rounds},
                            {"split_edges", sliver_refinement.split_edges},
                            {"stopped", sliver_refinement.stopped}};
  j["input_wedges"] = {{"narrowest_degrees", wedges.narrowest_degrees},
                       {"under_min_dihedral", wedges.narrow_edges}};
  return j;
}

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
  if (decimate_to > 0) j["decimated_to"] = decimate_to;
  if (!message.empty()) j["message"] = message;
  return j;
}

}  // namespace sheetmesh
