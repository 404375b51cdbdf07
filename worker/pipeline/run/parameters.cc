#include "worker/pipeline/run/parameters.h"

#include <cmath>
#include <cstdio>
#include <functional>

#include "absl/container/flat_hash_map.h"
#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_replace.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "common/assert.h"
#include "common/json_parse.h"
#include "common/json_text.h"
#include "common/status_macros.h"
#include "worker/pipeline/extract/extraction.h"
#include "worker/pipeline/run/parameter_rows.h"
#include "worker/pipeline/run/parameters_json.h"

namespace sheetmesh {
namespace {

using Json = nlohmann::json;

// A setting that does something (not false, not 0): two of one exclusive group clash only
// when both do.
bool Active(const ParamValue& v) {
  if (const bool* b = std::get_if<bool>(&v)) return *b;
  if (const double* d = std::get_if<double>(&v)) return *d != 0;
  return true;
}

// A relation between parameters that `options` breaks: the key to blame, its value, why.
struct Broken {
  std::string key, value, why;
};

// The relations between parameters, checked once every setting is in.
std::optional<Broken> BrokenRelation(const PipelineOptions& o) {
  const TetImproveOptions& im = o.volume.improve;
  if (im.insert_below_degrees > im.target_degrees) {
    return Broken{"improve.insert_below_degrees", absl::StrCat(im.insert_below_degrees),
                  absl::StrCat("must be at most improve.target_degrees = ", im.target_degrees)};
  }
  const ExtendOptions& detect = o.extraction.detect_extend;
  if (detect.radius_voxels > 0 && detect.radius_voxels < detect.half_thickness_voxels) {
    return Broken{"detect.R", absl::StrCat(detect.radius_voxels),
                  absl::StrCat("must be at least detect.t = ", detect.half_thickness_voxels,
                               " (a cylinder wider than it is thick)")};
  }
  if (o.output.split && !o.output.inp && !o.output.exo) {
    return Broken{"output.split", "true",
                  "needs inp or exo among output.volume_formats (the split mesh is written "
                  "only for mechanics)"};
  }
  if (o.surface.bricks.brick > 0 && o.surface.error_density > 0) {
    return Broken{
        "surface.bricks", absl::StrCat(o.surface.bricks.brick),
        absl::StrCat("cannot be combined with surface.error_density = ", o.surface.error_density,
                     " (the error's density is scaled over the whole sheet)")};
  }
  // A brick below its halo reads (1 + 2 halo / brick)^3 times its own voxels: at 1 voxel, a
  // pass per voxel that never ends (hardening, third round). The data's own floor (4 r + the
  // thickest run) is checked once the sheet is known (surface_builder.cc).
  const int brick = o.surface.bricks.brick;
  if (brick > 0 && brick < kMinSurfaceBrick) {
    return Broken{"surface.bricks", absl::StrCat(brick),
                  absl::StrCat("must be 0 (the surface built whole) or at least ",
                               kMinSurfaceBrick, " voxels")};
  }
  if (brick > 0 && o.surface.bricks.halo > brick) {
    return Broken{"surface.bricks", absl::StrCat(brick),
                  absl::StrCat("must be at least surface.bricks_halo = ", o.surface.bricks.halo,
                               " (a brick reads its halo on every side)")};
  }
  const RadiusSearchOptions& rs = o.radius_search;
  if (rs.max_radius_voxels != 0 && rs.max_radius_voxels < rs.min_radius_voxels) {
    return Broken{
        "radius_search.r_max", absl::StrCat(rs.max_radius_voxels),
        absl::StrCat("must be 0 or at least radius_search.r_min = ", rs.min_radius_voxels)};
  }
  return std::nullopt;
}

// Settings that follow another unless set: detect.scvd_r and recover.scvd_r of 0 take
// separate.r; flow and output.split turn the volume mesh on.
void ResolveFollowers(PipelineOptions& o) {
  if (o.flow.enabled || o.output.split) o.volume_mesh = true;  // they need the volume mesh
  ExtractionOptions& x = o.extraction;
  for (ExtendOptions* e : {&x.detect_extend, &x.recover_extend}) {
    *e = Following(*e, x.separation);
  }
}

// Whether some parameter key lies under `path` ("separate" for "separate.r").
bool IsGroup(const std::string& path) {
  const std::string prefix = path + ".";
  for (const ParamSpec& s : Parameters()) {
    if (s.key.compare(0, prefix.size(), prefix) == 0) return true;
  }
  return false;
}

std::string Canonical(absl::string_view name) { return absl::StrReplaceAll(name, {{"-", "_"}}); }

}  // namespace

std::string ParamSpec::name() const {
  absl::string_view k = key;
  absl::ConsumePrefix(&k, "input.");
  return absl::StrReplaceAll(k, {{".", "_"}});
}

const std::vector<ParamSpec>& Parameters() {
  static const std::vector<ParamSpec>* specs = [] {
    auto* out = new std::vector<ParamSpec>;
    for (const ParamRow& r : ParamRows()) out->push_back(r.spec);
    return out;
  }();
  return *specs;
}

const ParamRow& RowOf(const ParamSpec& spec) {
  const size_t i = static_cast<size_t>(&spec - Parameters().data());
  SM_ASSERT(i < ParamRows().size());
  return ParamRows()[i];
}

const ParamSpec* FindParameter(absl::string_view name) {
  static const auto* index = [] {
    auto* m = new absl::flat_hash_map<std::string, const ParamSpec*>;
    for (const ParamSpec& s : Parameters()) {
      (*m)[s.key] = &s;
      (*m)[s.name()] = &s;
    }
    return m;
  }();
  const std::string n = Canonical(name);
  auto it = index->find(n);
  if (it == index->end()) it = index->find(absl::StrReplaceAll(n, {{".", "_"}}));
  return it == index->end() ? nullptr : it->second;
}

const char* RenamedParameter(absl::string_view old_name) {
  const std::string n = Canonical(old_name);
  for (const Renamed& r : RenamedParameters()) {
    if (n == r.old_name) return r.new_key;
  }
  return nullptr;
}

std::optional<ParamValue> GetParameter(const ParamSpec& spec, const PipelineOptions& options) {
  return RowOf(spec).get(options);
}

absl::Status ParameterBuilder::Check(const ParamSpec& spec, const ParamValue& value,
                                     const std::string& display) const {
  if (spec.scope == ParamScope::kLocal && scope_ == ParamScope::kJob) {
    return absl::InvalidArgumentError(absl::StrCat(
        display, " (", spec.key,
        ") names a path or program of the machine that runs the pipeline; a job may not set "
        "it"));
  }
  if (!HasType(spec, value)) return BadValue(display, ShowValue(value), Expected(spec));
  const std::string why = Violation(RowOf(spec), value);
  if (!why.empty()) return BadValue(display, ShowValue(value), why);
  return absl::OkStatus();
}

absl::Status ParameterBuilder::Add(const ParamSpec& spec, ParamValue value, std::string display) {
  value = Widen(spec, std::move(value));
  SM_RETURN_IF_ERROR(Check(spec, value, display));
  entries_.push_back({&spec, std::move(value), std::move(display), source_});
  return absl::OkStatus();
}

absl::Status ParameterBuilder::AddJson(absl::string_view text, absl::string_view source) {
  SM_ASSIGN_OR_RETURN(const Json root, ParseJson(text, source));
  if (!root.is_object()) {
    return absl::InvalidArgumentError(
        absl::StrCat(source, ": '(top level)' = ", JsonText(root), " must be an object"));
  }
  const int this_source = ++source_;
  ++source_;  // settings added after this document are another source
  std::vector<Entry> added;
  // Walks objects by key path; a key is a parameter's key or a group of them.
  std::function<absl::Status(const Json&, const std::string&)> walk =
      [&](const Json& object, const std::string& path) -> absl::Status {
    for (auto it = object.begin(); it != object.end(); ++it) {
      const std::string key = path.empty() ? it.key() : absl::StrCat(path, ".", it.key());
      const Json& v = it.value();
      const ParamSpec* spec = nullptr;
      for (const ParamSpec& s : Parameters()) {
        if (s.key == key) spec = &s;
      }
      if (spec != nullptr && !(v.is_object() && spec->type != ParamType::kText)) {
        const std::string display = absl::StrCat(source, ": '", key, "'");
        std::optional<ParamValue> value = FromJson(*spec, v);
        if (!value) return BadValue(display, JsonText(v), Expected(*spec));
        SM_RETURN_IF_ERROR(Check(*spec, *value, display));
        added.push_back({spec, std::move(*value), display, this_source});
        continue;
      }
      if (v.is_object() && IsGroup(key)) {
        SM_RETURN_IF_ERROR(walk(v, key));
        continue;
      }
      if (const char* now = RenamedParameter(key)) {
        return absl::InvalidArgumentError(
            absl::StrCat(source, ": '", key, "' is now '", now,
                         "' (sheetmesh 0.9 gave every setting one name)"));
      }
      if (v.is_object() && spec != nullptr) {  // an old group under a new name: say what moved
        SM_RETURN_IF_ERROR(walk(v, key));
        continue;
      }
      std::vector<std::string> known;
      const std::string prefix = path.empty() ? "" : path + ".";
      for (const ParamSpec& s : Parameters()) {
        if (s.key.compare(0, prefix.size(), prefix) != 0) continue;
        const std::string rest = s.key.substr(prefix.size());
        const std::string first = rest.substr(0, rest.find('.'));
        if (known.empty() || known.back() != first) known.push_back(first);
      }
      return absl::InvalidArgumentError(absl::StrCat(
          source, ": unknown key '", key, "'; known here: ", absl::StrJoin(known, ", ")));
    }
    return absl::OkStatus();
  };
  SM_RETURN_IF_ERROR(walk(root, ""));
  for (Entry& e : added) entries_.push_back(std::move(e));
  return absl::OkStatus();
}

absl::StatusOr<PipelineOptions> ParameterBuilder::Build(PipelineOptions o) const {
  // Two settings of one exclusive group from one source contradict each other.
  for (size_t i = 0; i < entries_.size(); ++i) {
    const Entry& a = entries_[i];
    if (a.spec->exclusive.empty() || !Active(a.value)) continue;
    for (size_t j = i + 1; j < entries_.size(); ++j) {
      const Entry& b = entries_[j];
      if (b.source == a.source && b.spec != a.spec && b.spec->exclusive == a.spec->exclusive &&
          Active(b.value)) {
        return absl::InvalidArgumentError(
            absl::StrCat(a.display, " and ", b.display, " exclude each other; give one"));
      }
    }
  }
  for (bool presets : {true, false}) {
    for (const Entry& e : entries_) {
      if (e.spec->preset == presets) RowOf(*e.spec).set(e.value, o);
    }
  }
  ResolveFollowers(o);
  if (std::optional<Broken> b = BrokenRelation(o)) {
    // Blame the setting as its source spelt it, when one set it.
    std::string display = absl::StrCat("parameter ", b->key);
    for (const Entry& e : entries_) {
      if (e.spec->key == b->key) display = e.display;
    }
    return BadValue(display, b->value, b->why);
  }
  return o;
}

absl::Status CheckParameters(const PipelineOptions& options) {
  for (const ParamRow& row : ParamRows()) {
    std::optional<ParamValue> v = row.get(options);
    if (!v) continue;
    const std::string why = Violation(row, *v);
    if (!why.empty()) return BadValue(absl::StrCat("parameter ", row.spec.key), ShowValue(*v), why);
  }
  if (std::optional<Broken> b = BrokenRelation(options)) {
    return BadValue(absl::StrCat("parameter ", b->key), b->value, b->why);
  }
  return absl::OkStatus();
}

nlohmann::json ParametersJson(const PipelineOptions& options, bool include_local) {
  Json j = Json::object();
  for (const ParamRow& row : ParamRows()) {
    if (!include_local && row.spec.scope == ParamScope::kLocal) continue;
    std::optional<ParamValue> v = row.get(options);
    if (!v) continue;
    Json* at = &j;
    for (absl::string_view part : absl::StrSplit(row.spec.key, '.')) at = &(*at)[std::string(part)];
    *at = ToJson(*v);
  }
  return j;
}

std::string CanonicalParametersJson(const PipelineOptions& options, bool include_local) {
  return JsonText(ParametersJson(options, include_local));
}

std::string ParametersMarkdown() {
  const PipelineOptions defaults;
  std::string md =
      "| key | flag, proto field | type and range | default | what |\n"
      "|---|---|---|---|---|\n";
  for (const ParamSpec& s : Parameters()) {
    std::optional<ParamValue> d = GetParameter(s, defaults);
    std::string shown = d ? ShowValue(*d) : "unset";
    if (s.preset) shown = "\"extended\"";
    // A '|' inside a cell ("0 | (0, 1000]") would end it.
    auto cell = [](const std::string& text) { return absl::StrReplaceAll(text, {{"|", "\\|"}}); };
    absl::StrAppend(&md, "| `", s.key, "` | `--", s.name(), "` | ", cell(s.Describe()), " | `",
                    shown, "` | ", cell(s.doc),
                    s.scope == ParamScope::kLocal ? " (offline only)" : "", " |\n");
  }
  return md;
}

}  // namespace sheetmesh
