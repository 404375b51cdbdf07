// The report's part of the volume mesh: the `Fields()` its results declare, with the
// report's JSON names (run/pipeline_report.cc nests them).
#include <nlohmann/json.hpp>

#include "absl/strings/str_format.h"
#include "worker/pipeline/tet/plc.h"
#include "worker/pipeline/tet/split_mesh.h"
#include "worker/pipeline/tet/tet_improve.h"
#include "worker/pipeline/tet/tet_quality.h"
#include "worker/pipeline/tet/volume_mesh_stats.h"

namespace sheetmesh {

nlohmann::json QualityStat::Fields() const {
  return {{"min", min}, {"mean", mean}, {"histogram_range", {lo, hi}}, {"histogram", histogram}};
}

nlohmann::json SplitStats::Fields() const {
  return {{"sheet_nodes", sheet_nodes},    {"rim_nodes", rim_nodes},
          {"added_nodes", added_nodes},    {"interfaces", interfaces},
          {"closed_faces", closed_faces},  {"unsplit_faces", unsplit_faces},
          {"glued_regions", glued_regions}};
}

nlohmann::json TetQuality::Fields() const {
  return {{"min_dihedral_degrees", min_dihedral.Fields()},
          {"gamma", gamma.Fields()},
          {"edge_aspect", edge_aspect.Fields()},
          {"radius_aspect", radius_aspect.Fields()}};
}

std::string AngleWarning::Line() const {
  return absl::StrFormat(
      "min dihedral %.2f° under tet.min_dihedral = %g° at voxel (%.0f, %.0f, %.0f): %s", degrees,
      aim_degrees, at_voxel.x, at_voxel.y, at_voxel.z, cause);
}

nlohmann::json AngleWarning::Fields() const {
  return {{"degrees", degrees},
          {"aim_degrees", aim_degrees},
          {"at", {at.x, at.y, at.z}},
          {"at_voxel", {at_voxel.x, at_voxel.y, at_voxel.z}},
          {"corners_on_sheets", corners_on_sheets},
          {"cause", cause},
          {"text", Line()}};
}

nlohmann::json TetImproveReport::Fields() const {
  return {{"passes", passes},
          {"edge_removals", edge_removals},
          {"face_removals", face_removals},
          {"smoothing_moves", smoothing_moves},
          {"inserted_vertices", inserted_vertices},
          {"sheet_face_splits", sheet_face_splits},
          {"sheet_edge_splits", sheet_edge_splits},
          {"box_face_splits", box_face_splits},
          {"contracted_edges", contracted_edges},
          {"contracted_sheet_edges", contracted_sheet_edges},
          {"moved_sheet_vertices", moved_sheet_vertices},
          {"max_sheet_move_voxels", max_sheet_move},
          {"returned_sheet_vertices", returned_sheet_vertices},
          {"over_budget", over_budget},
          {"retries_skipped", retries_skipped},
          {"movable_vertices", movable_vertices},
          {"sliding_vertices", sliding_vertices},
          {"min_dihedral_before", min_dihedral_before},
          {"mean_dihedral_before", mean_dihedral_before},
          {"min_dihedral_after", min_dihedral_after},
          {"mean_dihedral_after", mean_dihedral_after},
          {"seconds", seconds},
          {"time_limited", time_limited}};
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
          {"straightened_junctions", straightened_junctions},
          {"opened_dihedral_wedges", opened_dihedral_wedges},
          {"opened_wedges", opened_wedges},
          {"closed_caps", closed_caps},
          {"collapsed_edges", collapsed_edges},
          {"split_long_edges", split_long_edges},
          {"mended_contacts", mended_contacts},
          {"mended_edge_contacts", mended_edge_contacts},
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
  if (angle_warning) j["angle_warning"] = angle_warning->Fields();
  j["voxels_per_tetrahedron"] = voxels_per_tet;
  j["volume"] = quality.volume;
  j["tetgen_switches"] = tetgen_switches;
  j["tetgen_seconds"] = tetgen_seconds;
  j["tetgen_tetrahedra"] = tetgen_tetrahedra;
  j["tetgen_recovery"] = tetgen_recovery;
  j["tetgen_seed_moves"] = seed_moves;
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
  j["second_try"] = {{"tried", second_try.tried},
                     {"min_dihedral_first", second_try.min_dihedral_first},
                     {"min_dihedral_second", second_try.min_dihedral_second},
                     {"kept", second_try.kept},
                     {"stopped", second_try.stopped}};
  j["input_wedges"] = {{"narrowest_degrees", wedges.narrowest_degrees},
                       {"under_min_dihedral", wedges.narrow_edges}};
  return j;
}

}  // namespace sheetmesh
