#include "worker/runtime/job_parameters.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "worker/pipeline/core/status_macros.h"
#include "worker/pipeline/run/pipeline_config.h"

namespace sheetmesh::runtime {
namespace {

absl::Status Bad(absl::string_view field, double value, absl::string_view why) {
  return absl::InvalidArgumentError(absl::StrCat("parameters.", field, " = ", value, " ", why));
}

absl::Status BadText(absl::string_view field, absl::string_view value, absl::string_view why) {
  return absl::InvalidArgumentError(absl::StrCat("parameters.", field, " = '", value, "' ", why));
}

}  // namespace

absl::StatusOr<PipelineOptions> ToPipelineOptions(const v1::PipelineParameters& p,
                                                  const v1::JobInput& input,
                                                  const std::string& volume_path) {
  PipelineOptions o;
  if (!p.config_json().empty()) {
    SM_RETURN_IF_ERROR(ApplyPipelineConfig(p.config_json(), "parameters.config_json", &o));
  }
  o.input.path = volume_path;
  // Input format.
  const v1::VolumeFormat& f = input.format();
  if (!f.format().empty()) o.input.open.format = f.format();
  if (f.dims_size() > 0) {
    if (f.dims_size() != 3)
      return absl::InvalidArgumentError(
          absl::StrCat("input.format.dims has ", f.dims_size(), " values, not 3"));
    o.input.open.raw_dims = Dims{f.dims(0), f.dims(1), f.dims(2)};
  }
  if (!f.dtype().empty()) {
    auto t = ParseDType(f.dtype());
    if (!t.ok()) return BadText("input.format.dtype", f.dtype(), "is not uint8, uint16 or float32");
    o.input.open.raw_dtype = *t;
  }
  if (!f.byte_order().empty()) {
    auto b = ParseByteOrder(f.byte_order());
    if (!b.ok()) return BadText("input.format.byte_order", f.byte_order(), "is not little or big");
    o.input.open.raw_byte_order = *b;
  }
  if (f.header_bytes() < 0)
    return Bad("input.format.header_bytes", f.header_bytes(), "must not be negative");
  o.input.open.raw_header_bytes = f.header_bytes();
  if (f.spacing_size() > 0) {
    if (f.spacing_size() != 3)
      return absl::InvalidArgumentError("input.format.spacing must have 3 values");
    o.input.open.spacing = Vec3(f.spacing(0), f.spacing(1), f.spacing(2));
  }
  if (f.origin_size() > 0) {
    if (f.origin_size() != 3)
      return absl::InvalidArgumentError("input.format.origin must have 3 values");
    o.input.open.origin = Vec3(f.origin(0), f.origin(1), f.origin(2));
  }
  if (!f.unit().empty()) o.input.open.unit = f.unit();
  // Sheet phase.
  if (p.labels_size() > 0 && p.window_size() > 0) {
    return absl::InvalidArgumentError("parameters.labels and parameters.window are exclusive");
  }
  if (p.labels_size() > 0) {
    o.input.selection = PhaseSelection::Labels({p.labels().begin(), p.labels().end()});
  }
  if (p.window_size() > 0) {
    if (p.window_size() != 2 || p.window(0) > p.window(1)) {
      return absl::InvalidArgumentError("parameters.window must be [lo, hi] with lo <= hi");
    }
    o.input.selection = PhaseSelection::Window(p.window(0), p.window(1));
  }
  // The typed fields are checked under their own names, so that an error names the field
  // the caller set (the checks below on the combined options name the config's keys).
  auto positive = [](absl::string_view field, bool has, double v) {
    return has && !(v > 0) ? Bad(field, v, "must be positive") : absl::OkStatus();
  };
  auto not_negative = [](absl::string_view field, bool has, double v) {
    return has && !(v >= 0) ? Bad(field, v, "must not be negative") : absl::OkStatus();
  };
  SM_RETURN_IF_ERROR(
      not_negative("refine_close_radius", p.has_refine_close_radius(), p.refine_close_radius()));
  SM_RETURN_IF_ERROR(
      not_negative("refine_open_radius", p.has_refine_open_radius(), p.refine_open_radius()));
  SM_RETURN_IF_ERROR(positive("detect_t", p.has_detect_t(), p.detect_t()));
  SM_RETURN_IF_ERROR(
      positive("detect_r_cylinder", p.has_detect_r_cylinder(), p.detect_r_cylinder()));
  SM_RETURN_IF_ERROR(not_negative("detect_rounds", p.has_detect_rounds(), p.detect_rounds()));
  SM_RETURN_IF_ERROR(positive("separate_r", p.has_separate_r(), p.separate_r()));
  if (p.has_d_ang() && !(p.d_ang() > 0 && p.d_ang() <= 180))
    return Bad("d_ang", p.d_ang(), "must be in (0, 180]");
  SM_RETURN_IF_ERROR(positive("recover_t", p.has_recover_t(), p.recover_t()));
  SM_RETURN_IF_ERROR(
      positive("recover_r_cylinder", p.has_recover_r_cylinder(), p.recover_r_cylinder()));
  SM_RETURN_IF_ERROR(not_negative("recover_rounds", p.has_recover_rounds(), p.recover_rounds()));
  SM_RETURN_IF_ERROR(positive("r", p.has_r(), p.r()));
  SM_RETURN_IF_ERROR(not_negative("generator_count", p.has_generator_count(), p.generator_count()));
  SM_RETURN_IF_ERROR(not_negative("lloyd_max_iter", p.has_lloyd_max_iter(), p.lloyd_max_iter()));
  SM_RETURN_IF_ERROR(not_negative("lloyd_tol", p.has_lloyd_tol(), p.lloyd_tol()));
  if (p.has_target_similarity() && !(p.target_similarity() > 0 && p.target_similarity() <= 1)) {
    return Bad("target_similarity", p.target_similarity(), "must be in (0, 1]");
  }
  if (p.has_tet_radius_edge_ratio() && p.tet_radius_edge_ratio() != 0 &&
      !(p.tet_radius_edge_ratio() >= 1)) {
    return Bad("tet_radius_edge_ratio", p.tet_radius_edge_ratio(),
               "must be 0 (none) or at least 1");
  }
  if (p.has_tet_min_dihedral() && !(p.tet_min_dihedral() >= 0 && p.tet_min_dihedral() < 70)) {
    return Bad("tet_min_dihedral", p.tet_min_dihedral(), "must be in [0, 70)");
  }
  SM_RETURN_IF_ERROR(not_negative("tet_max_volume", p.has_tet_max_volume(), p.tet_max_volume()));
  if (p.has_volume_lattice() && p.volume_lattice() != 0 &&
      !(p.volume_lattice() >= 0.25 && p.volume_lattice() <= 8)) {
    return Bad("volume_lattice", p.volume_lattice(), "must be 0 (none) or in [0.25, 8]");
  }
  for (int i = 0; i < p.labels_size(); ++i) {
    if (!std::isfinite(p.labels(i)))
      return Bad(absl::StrCat("labels[", i, "]"), p.labels(i), "must be finite");
  }
  // Extraction.
  ExtractionOptions& x = o.extraction;
  if (p.has_extract()) o.extract = p.extract();
  if (p.has_refine_close_radius()) x.refine_close_radius = p.refine_close_radius();
  if (p.has_refine_open_radius()) x.refine_open_radius = p.refine_open_radius();
  if (p.has_detect_t()) x.detect_extend.half_thickness_voxels = p.detect_t();
  if (p.has_detect_r_cylinder()) x.detect_extend.radius_voxels = p.detect_r_cylinder();
  if (p.has_detect_rounds()) x.detect_extend.max_rounds = p.detect_rounds();
  if (p.has_min_object_voxels()) x.min_object_voxels = p.min_object_voxels();
  if (p.has_separate_r()) {
    x.separation.radius_voxels = p.separate_r();
    x.detect_extend.scvd_radius_voxels = x.recover_extend.scvd_radius_voxels = p.separate_r();
  }
  if (p.has_d_ang()) x.separation.dihedral_degrees = p.d_ang();
  if (p.has_recover_t()) x.recover_extend.half_thickness_voxels = p.recover_t();
  if (p.has_recover_r_cylinder()) x.recover_extend.radius_voxels = p.recover_r_cylinder();
  if (p.has_recover_rounds()) x.recover_extend.max_rounds = p.recover_rounds();
  if (p.skip_refine()) x.refine = false;
  if (p.skip_detect()) x.detect = false;
  if (p.skip_separate()) x.separate = false;
  if (p.skip_remove_minor()) x.remove_minor = false;
  if (p.skip_recover()) x.recover = false;
  // Surface.
  if (p.method() == "paper") {
    const ScvdOptions keep = o.surface.scvd;
    o.surface = SurfaceOptions::Paper();
    o.surface.scvd.radius_voxels = keep.radius_voxels;
    o.surface.scvd.seed = keep.seed;
  } else if (!p.method().empty() && p.method() != "extended") {
    return BadText("method", p.method(), "is not extended or paper");
  }
  ScvdOptions& s = o.surface.scvd;
  if (p.has_r()) s.radius_voxels = p.r();
  if (p.has_seed()) s.seed = p.seed();
  if (p.has_generator_count()) s.generator_count = p.generator_count();
  if (p.has_lloyd_max_iter()) s.lloyd_max_iter = p.lloyd_max_iter();
  if (p.has_lloyd_tol()) s.lloyd_tol = p.lloyd_tol();
  if (p.radius_goal() == "best") {
    o.search_radius = true;
    o.radius_search.goal = RadiusGoal::kBestSimilarity;
  } else if (p.radius_goal() == "target") {
    o.search_radius = true;
    o.radius_search.goal = RadiusGoal::kTargetSimilarity;
  } else if (!p.radius_goal().empty()) {
    return BadText("radius_goal", p.radius_goal(), "is not best or target");
  }
  if (p.has_target_similarity()) o.radius_search.target_similarity = p.target_similarity();
  if (p.similarity_model() == "vertex") {
    o.score.height = o.radius_search.height = PrismHeight::kVertex;
  } else if (!p.similarity_model().empty() && p.similarity_model() != "face") {
    return BadText("similarity_model", p.similarity_model(), "is not face or vertex");
  }
  if (p.has_hausdorff()) o.score.hausdorff = p.hausdorff();
  // Volume mesh.
  if (p.has_volume_mesh()) o.volume_mesh = p.volume_mesh();
  TetgenOptions& t = o.volume.tetgen;
  if (p.has_tet_radius_edge_ratio()) t.max_radius_edge_ratio = p.tet_radius_edge_ratio();
  if (p.has_tet_min_dihedral()) t.min_dihedral_degrees = p.tet_min_dihedral();
  if (p.has_tet_max_volume()) t.max_volume = p.tet_max_volume();
  if (p.has_tet_steiner_on_sheets()) t.steiner_on_sheets = p.tet_steiner_on_sheets();
  if (p.has_repair()) o.volume.plc.repair = p.repair();
  if (p.has_volume_lattice()) o.volume.plc.lattice = p.volume_lattice();
  const absl::Status valid = ValidatePipelineOptions(o);
  if (!valid.ok()) return absl::InvalidArgumentError(absl::StrCat("parameters: ", valid.message()));
  return o;
}

}  // namespace sheetmesh::runtime
