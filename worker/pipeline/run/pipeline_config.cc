#include "worker/pipeline/run/pipeline_config.h"

#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "worker/pipeline/core/status_macros.h"

namespace sheetmesh {
namespace {

using Json = nlohmann::json;

// Reads typed values at a key path, collecting the first error.
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  absl::Status Error(const std::string& path, const Json& v, absl::string_view why) const {
    return absl::InvalidArgumentError(
        absl::StrCat(source_, ": '", path, "' = ", v.dump(), " ", why));
  }

  absl::Status Number(const Json& v, const std::string& path, double* out) const {
    if (!v.is_number()) return Error(path, v, "must be a number");
    *out = v.get<double>();
    return absl::OkStatus();
  }
  template <class Int>
  absl::Status Integer(const Json& v, const std::string& path, Int* out) const {
    if (!v.is_number_integer()) return Error(path, v, "must be an integer");
    const int64_t x = v.get<int64_t>();
    if (std::is_unsigned_v<Int> && x < 0) return Error(path, v, "must not be negative");
    *out = static_cast<Int>(x);
    return absl::OkStatus();
  }
  absl::Status Bool(const Json& v, const std::string& path, bool* out) const {
    if (!v.is_boolean()) return Error(path, v, "must be true or false");
    *out = v.get<bool>();
    return absl::OkStatus();
  }
  absl::Status String(const Json& v, const std::string& path, std::string* out) const {
    if (!v.is_string()) return Error(path, v, "must be a string");
    *out = v.get<std::string>();
    return absl::OkStatus();
  }
  absl::Status Vec(const Json& v, const std::string& path, Vec3* out) const {
    if (!v.is_array() || v.size() != 3) return Error(path, v, "must be three numbers");
    for (int k = 0; k < 3; ++k) {
      if (!v[k].is_number()) return Error(path, v, "must be three numbers");
      (*out)[k] = v[k].get<double>();
    }
    return absl::OkStatus();
  }
  absl::Status Numbers(const Json& v, const std::string& path, std::vector<double>* out) const {
    if (!v.is_array() || v.empty()) return Error(path, v, "must be a non-empty list of numbers");
    out->clear();
    for (const Json& x : v) {
      if (!x.is_number()) return Error(path, v, "must be a non-empty list of numbers");
      out->push_back(x.get<double>());
    }
    return absl::OkStatus();
  }

  // Calls handlers[key] for each key of object `v`; unknown keys are an error.
  absl::Status Object(
      const Json& v, const std::string& path,
      const std::map<std::string, std::function<absl::Status(const Json&, const std::string&)>>&
          handlers) const {
    if (!v.is_object()) return Error(path.empty() ? "(top level)" : path, v, "must be an object");
    for (auto it = v.begin(); it != v.end(); ++it) {
      const std::string key = path.empty() ? it.key() : absl::StrCat(path, ".", it.key());
      auto h = handlers.find(it.key());
      if (h == handlers.end()) {
        std::vector<std::string> known;
        for (const auto& [k, _] : handlers) known.push_back(k);
        return absl::InvalidArgumentError(absl::StrCat(
            source_, ": unknown key '", key, "'; known here: ", absl::StrJoin(known, ", ")));
      }
      SM_RETURN_IF_ERROR(h->second(it.value(), key));
    }
    return absl::OkStatus();
  }

 private:
  std::string source_;
};

using Handlers =
    std::map<std::string, std::function<absl::Status(const Json&, const std::string&)>>;

Handlers ExtendHandlers(const Reader& rd, bool* enabled, ExtendOptions* e) {
  return {
      {"enabled", [=, &rd](const Json& v, const std::string& p) { return rd.Bool(v, p, enabled); }},
      {"t", [=, &rd](const Json& v,
                     const std::string& p) { return rd.Number(v, p, &e->half_thickness_voxels); }},
      {"R", [=, &rd](const Json& v,
                     const std::string& p) { return rd.Number(v, p, &e->radius_voxels); }},
      {"rounds",
       [=, &rd](const Json& v, const std::string& p) { return rd.Integer(v, p, &e->max_rounds); }},
      {"r", [=, &rd](const Json& v,
                     const std::string& p) { return rd.Number(v, p, &e->scvd_radius_voxels); }},
  };
}

}  // namespace

absl::Status ApplyPipelineConfig(absl::string_view text, absl::string_view source,
                                 PipelineOptions* o) {
  const Reader rd{std::string(source)};
  Json root;
  try {
    root = Json::parse(text.begin(), text.end());
  } catch (const Json::parse_error& e) {
    return absl::InvalidArgumentError(absl::StrCat(source, ": not valid JSON: ", e.what()));
  }
  ExtractionOptions& x = o->extraction;
  SurfaceOptions& s = o->surface;
  const Handlers input = {
      {"labels",
       [&](const Json& v, const std::string& p) {
         std::vector<double> l;
         SM_RETURN_IF_ERROR(rd.Numbers(v, p, &l));
         o->input.selection = PhaseSelection::Labels(l);
         return absl::OkStatus();
       }},
      {"window",
       [&](const Json& v, const std::string& p) {
         std::vector<double> w;
         SM_RETURN_IF_ERROR(rd.Numbers(v, p, &w));
         if (w.size() != 2 || w[0] > w[1]) return rd.Error(p, v, "must be [lo, hi] with lo <= hi");
         o->input.selection = PhaseSelection::Window(w[0], w[1]);
         return absl::OkStatus();
       }},
      {"dims",
       [&](const Json& v, const std::string& p) {
         Vec3 d;
         SM_RETURN_IF_ERROR(rd.Vec(v, p, &d));
         o->input.open.raw_dims = Dims{int64_t(d.x), int64_t(d.y), int64_t(d.z)};
         return absl::OkStatus();
       }},
      {"dtype",
       [&](const Json& v, const std::string& p) {
         std::string t;
         SM_RETURN_IF_ERROR(rd.String(v, p, &t));
         auto d = ParseDType(t);
         if (!d.ok()) return rd.Error(p, v, "is not uint8, uint16 or float32");
         o->input.open.raw_dtype = *d;
         return absl::OkStatus();
       }},
      {"byte_order",
       [&](const Json& v, const std::string& p) {
         std::string t;
         SM_RETURN_IF_ERROR(rd.String(v, p, &t));
         auto b = ParseByteOrder(t);
         if (!b.ok()) return rd.Error(p, v, "is not little or big");
         o->input.open.raw_byte_order = *b;
         return absl::OkStatus();
       }},
      {"header_bytes",
       [&](const Json& v, const std::string& p) {
         return rd.Integer(v, p, &o->input.open.raw_header_bytes);
       }},
      {"format",
       [&](const Json& v, const std::string& p) { return rd.String(v, p, &o->input.open.format); }},
      {"vdb_grid", [&](const Json& v,
                       const std::string& p) { return rd.String(v, p, &o->input.open.vdb_grid); }},
      {"spacing",
       [&](const Json& v, const std::string& p) {
         Vec3 sp;
         SM_RETURN_IF_ERROR(rd.Vec(v, p, &sp));
         o->input.open.spacing = sp;
         return absl::OkStatus();
       }},
      {"origin",
       [&](const Json& v, const std::string& p) {
         Vec3 og;
         SM_RETURN_IF_ERROR(rd.Vec(v, p, &og));
         o->input.open.origin = og;
         return absl::OkStatus();
       }},
      {"unit",
       [&](const Json& v, const std::string& p) { return rd.String(v, p, &o->input.open.unit); }},
      {"mask",
       [&](const Json& v, const std::string& p) { return rd.String(v, p, &o->input.mask_path); }},
      {"mask_labels",
       [&](const Json& v, const std::string& p) {
         std::vector<double> l;
         SM_RETURN_IF_ERROR(rd.Numbers(v, p, &l));
         o->input.mask_selection = PhaseSelection::Labels(l);
         return absl::OkStatus();
       }},
  };
  bool remove_minor = x.remove_minor;
  const Handlers top = {
      {"input", [&](const Json& v, const std::string& p) { return rd.Object(v, p, input); }},
      {"extract", [&](const Json& v, const std::string& p) { return rd.Bool(v, p, &o->extract); }},
      {"M",
       [&](const Json& v, const std::string& p) { return rd.Integer(v, p, &x.min_object_voxels); }},
      {"refine",
       [&](const Json& v, const std::string& p) {
         return rd.Object(
             v, p,
             {
                 {"enabled",
                  [&](const Json& w, const std::string& q) { return rd.Bool(w, q, &x.refine); }},
                 {"close_radius",
                  [&](const Json& w, const std::string& q) {
                    return rd.Integer(w, q, &x.refine_close_radius);
                  }},
                 {"open_radius",
                  [&](const Json& w, const std::string& q) {
                    return rd.Integer(w, q, &x.refine_open_radius);
                  }},
             });
       }},
      {"detect",
       [&](const Json& v, const std::string& p) {
         return rd.Object(v, p, ExtendHandlers(rd, &x.detect, &x.detect_extend));
       }},
      {"recover",
       [&](const Json& v, const std::string& p) {
         return rd.Object(v, p, ExtendHandlers(rd, &x.recover, &x.recover_extend));
       }},
      {"separate",
       [&](const Json& v, const std::string& p) {
         return rd.Object(
             v, p,
             {
                 {"enabled",
                  [&](const Json& w, const std::string& q) { return rd.Bool(w, q, &x.separate); }},
                 {"r",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &x.separation.radius_voxels);
                  }},
                 {"D_ang",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &x.separation.dihedral_degrees);
                  }},
             });
       }},
      {"remove_minor",
       [&](const Json& v, const std::string& p) {
         return rd.Object(v, p, {{"enabled", [&](const Json& w, const std::string& q) {
                                    return rd.Bool(w, q, &remove_minor);
                                  }}});
       }},
      {"surface",
       [&](const Json& v, const std::string& p) {
         return rd.Object(
             v, p,
             {
                 {"r",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &s.scvd.radius_voxels);
                  }},
                 {"seed", [&](const Json& w,
                              const std::string& q) { return rd.Integer(w, q, &s.scvd.seed); }},
                 {"generators",
                  [&](const Json& w, const std::string& q) {
                    return rd.Integer(w, q, &s.scvd.generator_count);
                  }},
                 {"thickness",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &s.scvd.mean_thickness_voxels);
                  }},
                 {"lloyd_max_iter",
                  [&](const Json& w, const std::string& q) {
                    return rd.Integer(w, q, &s.scvd.lloyd_max_iter);
                  }},
                 {"lloyd_tol",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &s.scvd.lloyd_tol);
                  }},
                 {"fold_angle",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &s.triangles.fold_angle_degrees);
                  }},
                 {"rim", [&](const Json& w,
                             const std::string& q) { return rd.Bool(w, q, &s.triangles.rim); }},
                 {"method",
                  [&](const Json& w, const std::string& q) {
                    std::string m;
                    SM_RETURN_IF_ERROR(rd.String(w, q, &m));
                    if (m == "paper") {
                      const ScvdOptions keep = s.scvd;
                      s = SurfaceOptions::Paper();
                      s.scvd.radius_voxels = keep.radius_voxels;
                      s.scvd.seed = keep.seed;
                    } else if (m != "extended") {
                      return rd.Error(q, w, "is not extended or paper");
                    }
                    return absl::OkStatus();
                  }},
                 {"placement",
                  [&](const Json& w, const std::string& q) {
                    std::string m;
                    SM_RETURN_IF_ERROR(rd.String(w, q, &m));
                    if (m == "generator")
                      s.placement = VertexPlacement::kGenerator;
                    else if (m == "centroid")
                      s.placement = VertexPlacement::kCentroid;
                    else
                      return rd.Error(q, w, "is not generator or centroid");
                    return absl::OkStatus();
                  }},
                 {"thickness_measure",
                  [&](const Json& w, const std::string& q) {
                    std::string m;
                    SM_RETURN_IF_ERROR(rd.String(w, q, &m));
                    if (m == "axis_runs")
                      s.thickness = ThicknessMeasure::kAxisRuns;
                    else if (m == "normal")
                      s.thickness = ThicknessMeasure::kNormal;
                    else
                      return rd.Error(q, w, "is not axis_runs or normal");
                    return absl::OkStatus();
                  }},
                 {"domain",
                  [&](const Json& w, const std::string& q) {
                    std::string m;
                    SM_RETURN_IF_ERROR(rd.String(w, q, &m));
                    if (m == "voxels")
                      s.scvd.domain = ScvdDomain::kVoxels;
                    else if (m == "columns")
                      s.scvd.domain = ScvdDomain::kColumns;
                    else if (m == "auto")
                      s.scvd.domain = ScvdDomain::kAuto;
                    else
                      return rd.Error(q, w, "is not voxels, columns or auto");
                    return absl::OkStatus();
                  }},
             });
       }},
      {"radius_search",
       [&](const Json& v, const std::string& p) {
         return rd.Object(v, p,
                          {
                              {"goal",
                               [&](const Json& w, const std::string& q) {
                                 std::string g;
                                 SM_RETURN_IF_ERROR(rd.String(w, q, &g));
                                 if (g == "none") {
                                   o->search_radius = false;
                                 } else if (g == "best") {
                                   o->search_radius = true;
                                   o->radius_search.goal = RadiusGoal::kBestSimilarity;
                                 } else if (g == "target") {
                                   o->search_radius = true;
                                   o->radius_search.goal = RadiusGoal::kTargetSimilarity;
                                 } else {
                                   return rd.Error(q, w, "is not none, best or target");
                                 }
                                 return absl::OkStatus();
                               }},
                              {"target_similarity",
                               [&](const Json& w, const std::string& q) {
                                 return rd.Number(w, q, &o->radius_search.target_similarity);
                               }},
                              {"r_min",
                               [&](const Json& w, const std::string& q) {
                                 return rd.Number(w, q, &o->radius_search.min_radius_voxels);
                               }},
                              {"r_max",
                               [&](const Json& w, const std::string& q) {
                                 return rd.Number(w, q, &o->radius_search.max_radius_voxels);
                               }},
                          });
       }},
      {"similarity",
       [&](const Json& v, const std::string& p) {
         return rd.Object(v, p,
                          {
                              {"model",
                               [&](const Json& w, const std::string& q) {
                                 std::string m;
                                 SM_RETURN_IF_ERROR(rd.String(w, q, &m));
                                 if (m == "face")
                                   o->score.height = PrismHeight::kFace;
                                 else if (m == "vertex")
                                   o->score.height = PrismHeight::kVertex;
                                 else
                                   return rd.Error(q, w, "is not face or vertex");
                                 o->radius_search.height = o->score.height;
                                 return absl::OkStatus();
                               }},
                              {"hausdorff",
                               [&](const Json& w, const std::string& q) {
                                 return rd.Bool(w, q, &o->score.hausdorff);
                               }},
                              {"grid_rates",
                               [&](const Json& w, const std::string& q) {
                                 if (!w.is_array())
                                   return rd.Error(q, w, "must be a list of integers >= 1");
                                 o->score.grid_rates.clear();
                                 for (const Json& k : w) {
                                   if (!k.is_number_integer() || k.get<int>() < 1)
                                     return rd.Error(q, w, "must be a list of integers >= 1");
                                   o->score.grid_rates.push_back(k.get<int>());
                                 }
                                 return absl::OkStatus();
                               }},
                          });
       }},
      {"volume_mesh",
       [&](const Json& v, const std::string& p) {
         return rd.Object(
             v, p,
             {
                 {"enabled", [&](const Json& w,
                                 const std::string& q) { return rd.Bool(w, q, &o->volume_mesh); }},
                 {"radius_edge_ratio",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.tetgen.max_radius_edge_ratio);
                  }},
                 {"min_dihedral",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.tetgen.min_dihedral_degrees);
                  }},
                 {"max_volume",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.tetgen.max_volume);
                  }},
                 {"steiner_on_sheets",
                  [&](const Json& w, const std::string& q) {
                    return rd.Bool(w, q, &o->volume.tetgen.steiner_on_sheets);
                  }},
                 {"time_limit_seconds",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.tetgen.time_limit_seconds);
                  }},
                 {"memory_limit_bytes",
                  [&](const Json& w, const std::string& q) {
                    return rd.Integer(w, q, &o->volume.tetgen.memory_limit_bytes);
                  }},
                 {"tetgen",
                  [&](const Json& w, const std::string& q) {
                    return rd.String(w, q, &o->volume.tetgen.program);
                  }},
                 {"repair",
                  [&](const Json& w, const std::string& q) {
                    return rd.Bool(w, q, &o->volume.plc.repair);
                  }},
                 {"snap_voxels",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.plc.snap_voxels);
                  }},
                 {"snap_clear_voxels",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.plc.snap_clear_voxels);
                  }},
                 {"flip_fold_degrees",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.plc.flip_fold_degrees);
                  }},
                 {"cap_degrees",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.plc.cap_degrees);
                  }},
                 {"overlap_voxels",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.plc.overlap_voxels);
                  }},
                 {"overlap_degrees",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.plc.overlap_degrees);
                  }},
                 {"wedge_degrees",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.plc.wedge_degrees);
                  }},
                 {"wedge_voxels",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.plc.wedge_voxels);
                  }},
                 {"lattice",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.plc.lattice);
                  }},
                 {"improve_passes",
                  [&](const Json& w, const std::string& q) {
                    return rd.Integer(w, q, &o->volume.improve.passes);
                  }},
                 {"improve_target_degrees",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.improve.target_degrees);
                  }},
                 {"improve_insert_below_degrees",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.improve.insert_below_degrees);
                  }},
                 {"improve_floor_degrees",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.improve.smoothing_floor_degrees);
                  }},
                 {"improve_split_sheets_below_degrees",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.improve.split_sheets_below_degrees);
                  }},
                 {"improve_radius_weight",
                  [&](const Json& w, const std::string& q) {
                    return rd.Number(w, q, &o->volume.improve.radius_weight);
                  }},
             });
       }},
      {"output",
       [&](const Json& v, const std::string& p) {
         return rd.Object(
             v, p,
             {
                 {"formats",
                  [&](const Json& w, const std::string& q) {
                    if (!w.is_array()) return rd.Error(q, w, "must be a list of ply, vtp, obj");
                    o->output.ply = o->output.vtp = o->output.obj = false;
                    for (const Json& f : w) {
                      const std::string n = f.is_string() ? f.get<std::string>() : "";
                      if (n == "ply")
                        o->output.ply = true;
                      else if (n == "vtp")
                        o->output.vtp = true;
                      else if (n == "obj")
                        o->output.obj = true;
                      else
                        return rd.Error(q, w, "must be a list of ply, vtp, obj");
                    }
                    return absl::OkStatus();
                  }},
                 {"model", [&](const Json& w,
                               const std::string& q) { return rd.Bool(w, q, &o->output.model); }},
                 {"volume_formats",
                  [&](const Json& w, const std::string& q) {
                    if (!w.is_array()) return rd.Error(q, w, "must be a list of vtu, msh, inp");
                    o->output.vtu = o->output.msh = o->output.inp = false;
                    for (const Json& f : w) {
                      const std::string n = f.is_string() ? f.get<std::string>() : "";
                      if (n == "vtu")
                        o->output.vtu = true;
                      else if (n == "msh")
                        o->output.msh = true;
                      else if (n == "inp")
                        o->output.inp = true;
                      else
                        return rd.Error(q, w, "must be a list of vtu, msh, inp");
                    }
                    return absl::OkStatus();
                  }},
             });
       }},
  };
  SM_RETURN_IF_ERROR(rd.Object(root, "", top));
  x.remove_minor = remove_minor;
  const absl::Status valid = ValidatePipelineOptions(*o);
  if (!valid.ok()) return absl::InvalidArgumentError(absl::StrCat(source, ": ", valid.message()));
  return absl::OkStatus();
}

absl::Status ValidatePipelineOptions(const PipelineOptions& o) {
  auto bad = [](absl::string_view name, double v, absl::string_view why) {
    return absl::InvalidArgumentError(absl::StrCat("parameter ", name, " = ", v, " ", why));
  };
  const SurfaceOptions& s = o.surface;
  if (!(s.scvd.radius_voxels > 0)) return bad("r", s.scvd.radius_voxels, "must be positive");
  if (s.scvd.lloyd_max_iter < 0)
    return bad("lloyd_max_iter", s.scvd.lloyd_max_iter, "must not be negative");
  if (!(s.scvd.lloyd_tol >= 0)) return bad("lloyd_tol", s.scvd.lloyd_tol, "must not be negative");
  if (s.scvd.generator_count < 0)
    return bad("generators", s.scvd.generator_count, "must not be negative");
  if (!(s.triangles.fold_angle_degrees >= 0 && s.triangles.fold_angle_degrees < 180)) {
    return bad("fold_angle", s.triangles.fold_angle_degrees, "must be in [0, 180)");
  }
  {
    const ExtractionOptions& x = o.extraction;
    if (x.refine_close_radius < 0)
      return bad("refine.close_radius", x.refine_close_radius, "must not be negative");
    if (x.refine_open_radius < 0)
      return bad("refine.open_radius", x.refine_open_radius, "must not be negative");
    if (!(x.separation.radius_voxels > 0))
      return bad("separate.r", x.separation.radius_voxels, "must be positive");
    if (!(x.separation.dihedral_degrees > 0 && x.separation.dihedral_degrees <= 180)) {
      return bad("separate.D_ang", x.separation.dihedral_degrees, "must be in (0, 180]");
    }
    for (const auto& [name, e] :
         {std::pair{"detect", &x.detect_extend}, std::pair{"recover", &x.recover_extend}}) {
      if (!(e->half_thickness_voxels > 0))
        return bad(absl::StrCat(name, ".t"), e->half_thickness_voxels, "must be positive");
      if (!(e->radius_voxels > 0))
        return bad(absl::StrCat(name, ".R"), e->radius_voxels, "must be positive");
      if (!(e->scvd_radius_voxels > 0))
        return bad(absl::StrCat(name, ".r"), e->scvd_radius_voxels, "must be positive");
      if (e->max_rounds < 0)
        return bad(absl::StrCat(name, ".rounds"), e->max_rounds, "must not be negative");
    }
  }
  if (o.search_radius) {
    const RadiusSearchOptions& r = o.radius_search;
    if (!(r.target_similarity <= 1.0))
      return bad("target_similarity", r.target_similarity, "must be at most 1");
    if (!(r.min_radius_voxels > 0)) return bad("r_min", r.min_radius_voxels, "must be positive");
  }
  const TetgenOptions& tg = o.volume.tetgen;
  if (tg.max_radius_edge_ratio != 0 && !(tg.max_radius_edge_ratio >= 1.0)) {
    return bad("volume_mesh.radius_edge_ratio", tg.max_radius_edge_ratio,
               "must be 0 (none) or at least 1");
  }
  if (!(tg.min_dihedral_degrees >= 0 && tg.min_dihedral_degrees < 70)) {
    return bad("volume_mesh.min_dihedral", tg.min_dihedral_degrees, "must be in [0, 70)");
  }
  if (!(tg.max_volume >= 0))
    return bad("volume_mesh.max_volume", tg.max_volume, "must not be negative");
  if (!(tg.time_limit_seconds > 0))
    return bad("volume_mesh.time_limit_seconds", tg.time_limit_seconds, "must be positive");
  if (!(o.volume.plc.snap_voxels >= 0))
    return bad("volume_mesh.snap_voxels", o.volume.plc.snap_voxels, "must not be negative");
  if (!(o.volume.plc.snap_clear_voxels >= 0 && o.volume.plc.snap_clear_voxels <= 10)) {
    return bad("volume_mesh.snap_clear_voxels", o.volume.plc.snap_clear_voxels,
               "must be in [0, 10]");
  }
  if (!(o.volume.plc.flip_fold_degrees >= 0 && o.volume.plc.flip_fold_degrees < 90)) {
    return bad("volume_mesh.flip_fold_degrees", o.volume.plc.flip_fold_degrees,
               "must be in [0, 90)");
  }
  if (!(o.volume.plc.cap_degrees > 90 && o.volume.plc.cap_degrees <= 180)) {
    return bad("volume_mesh.cap_degrees", o.volume.plc.cap_degrees, "must be in (90, 180]");
  }
  if (!(o.volume.plc.overlap_voxels >= 0 && o.volume.plc.overlap_voxels <= 10)) {
    return bad("volume_mesh.overlap_voxels", o.volume.plc.overlap_voxels, "must be in [0, 10]");
  }
  if (!(o.volume.plc.lattice == 0 || (o.volume.plc.lattice >= 0.25 && o.volume.plc.lattice <= 8))) {
    return bad("volume_mesh.lattice", o.volume.plc.lattice, "must be 0 or in [0.25, 8]");
  }
  if (!(o.volume.plc.overlap_degrees >= 0 && o.volume.plc.overlap_degrees < 90)) {
    return bad("volume_mesh.overlap_degrees", o.volume.plc.overlap_degrees, "must be in [0, 90)");
  }
  if (!(o.volume.plc.wedge_degrees >= 0 && o.volume.plc.wedge_degrees <= 30)) {
    return bad("volume_mesh.wedge_degrees", o.volume.plc.wedge_degrees, "must be in [0, 30]");
  }
  if (!(o.volume.plc.wedge_voxels >= 0 && o.volume.plc.wedge_voxels <= 5)) {
    return bad("volume_mesh.wedge_voxels", o.volume.plc.wedge_voxels, "must be in [0, 5]");
  }
  const TetImproveOptions& im = o.volume.improve;
  if (!(im.passes >= 0 && im.passes <= 100)) {
    return bad("volume_mesh.improve_passes", im.passes, "must be in [0, 100]");
  }
  if (!(im.target_degrees >= 0 && im.target_degrees <= 70.6)) {
    return bad("volume_mesh.improve_target_degrees", im.target_degrees, "must be in [0, 70.6]");
  }
  if (!(im.insert_below_degrees >= 0 && im.insert_below_degrees <= im.target_degrees)) {
    return bad("volume_mesh.improve_insert_below_degrees", im.insert_below_degrees,
               "must be in [0, improve_target_degrees]");
  }
  if (!(im.smoothing_floor_degrees >= 0 && im.smoothing_floor_degrees <= 70.6)) {
    return bad("volume_mesh.improve_floor_degrees", im.smoothing_floor_degrees,
               "must be in [0, 70.6]");
  }
  if (!(im.split_sheets_below_degrees >= 0 && im.split_sheets_below_degrees <= 70.6)) {
    return bad("volume_mesh.improve_split_sheets_below_degrees", im.split_sheets_below_degrees,
               "must be in [0, 70.6]");
  }
  if (!(im.radius_weight >= 0 && im.radius_weight <= 1)) {
    return bad("volume_mesh.improve_radius_weight", im.radius_weight, "must be in [0, 1]");
  }
  for (int k : o.score.grid_rates) {
    if (k < 1) return bad("grid_rates", k, "must be >= 1");
  }
  return absl::OkStatus();
}

}  // namespace sheetmesh
