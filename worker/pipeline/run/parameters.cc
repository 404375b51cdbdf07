#include "worker/pipeline/run/parameters.h"

#include <cassert>
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
#include "common/json_text.h"
#include "common/status_macros.h"
#include "worker/pipeline/run/parameter_rows.h"
#include "worker/pipeline/run/parameters_json.h"

namespace sheetmesh {
namespace {

using Json = nlohmann::json;

const char* TypeName(ParamType t) {
  switch (t) {
    case ParamType::kBool:
      return "bool";
    case ParamType::kInteger:
      return "integer";
    case ParamType::kNumber:
      return "number";
    case ParamType::kChoice:
      return "one of";
    case ParamType::kText:
      return "text";
    case ParamType::kNumbers:
      return "numbers";
    case ParamType::kIntegers:
      return "integers";
    case ParamType::kChoices:
      return "list of";
  }
  return "";
}

// "5", "true", "\"paper\"", "[2,3,4]".
std::string Show(const ParamValue& v) { return JsonText(ToJson(v)); }

absl::Status Bad(const std::string& display, const std::string& value, absl::string_view why) {
  return absl::InvalidArgumentError(absl::StrCat(display, " = ", value, " ", why));
}

// What a value must be, for the message when it is not.
std::string Expected(const ParamSpec& s) {
  const bool list = s.type == ParamType::kNumbers || s.type == ParamType::kIntegers ||
                    s.type == ParamType::kChoices;
  std::string what;
  switch (s.type) {
    case ParamType::kBool:
      return "must be true or false";
    case ParamType::kChoice:
      return absl::StrCat("must be one of ", absl::StrJoin(s.choices, ", "));
    case ParamType::kText:
      return "must be a string";
    case ParamType::kChoices:
      what = absl::StrCat("names from ", absl::StrJoin(s.choices, ", "));
      break;
    default:
      what = absl::StrCat(
          s.type == ParamType::kInteger || s.type == ParamType::kIntegers ? "integer" : "number",
          list ? "s" : "", " in ", s.range.text);
  }
  if (!list) return absl::StrCat("must be ", what[0] == 'i' ? "an " : "a ", what);
  if (s.count > 0) return absl::StrCat("must be ", s.count, " ", what);
  return absl::StrCat("must be a ", s.allow_empty ? "" : "non-empty ", "list of ", what);
}

// The JSON value as the row's type, or nullopt when it is not of that type.
std::optional<ParamValue> FromJson(const ParamSpec& s, const Json& v) {
  auto integer = [](const Json& x) -> std::optional<int64_t> {
    if (x.is_number_integer()) {
      if (x.is_number_unsigned() && x.get<uint64_t>() > uint64_t{INT64_MAX}) return std::nullopt;
      return x.get<int64_t>();
    }
    if (x.is_number_float()) {
      const double d = x.get<double>();
      if (std::isfinite(d) && d == std::floor(d) && std::abs(d) < 9.2e18) return int64_t(d);
    }
    return std::nullopt;
  };
  // A single value where a list is expected is a list of one ("labels": 255).
  const Json list = v.is_array() ? v : Json::array({v});
  switch (s.type) {
    case ParamType::kBool:
      if (v.is_boolean()) return ParamValue(v.get<bool>());
      return std::nullopt;
    case ParamType::kInteger:
      if (auto i = integer(v)) return ParamValue(*i);
      return std::nullopt;
    case ParamType::kNumber:
      if (v.is_number()) return ParamValue(v.get<double>());
      return std::nullopt;
    case ParamType::kChoice:
    case ParamType::kText:
      if (v.is_string()) return ParamValue(v.get<std::string>());
      return std::nullopt;
    case ParamType::kNumbers: {
      std::vector<double> out;
      for (const Json& x : list) {
        if (!x.is_number()) return std::nullopt;
        out.push_back(x.get<double>());
      }
      return ParamValue(out);
    }
    case ParamType::kIntegers: {
      std::vector<int64_t> out;
      for (const Json& x : list) {
        auto i = integer(x);
        if (!i) return std::nullopt;
        out.push_back(*i);
      }
      return ParamValue(out);
    }
    case ParamType::kChoices: {
      std::vector<std::string> out;
      for (const Json& x : list) {
        if (!x.is_string()) return std::nullopt;
        out.push_back(x.get<std::string>());
      }
      return ParamValue(out);
    }
  }
  return std::nullopt;
}

bool HasType(const ParamSpec& s, const ParamValue& v) {
  switch (s.type) {
    case ParamType::kBool:
      return std::holds_alternative<bool>(v);
    case ParamType::kInteger:
      return std::holds_alternative<int64_t>(v);
    case ParamType::kNumber:
      return std::holds_alternative<double>(v);
    case ParamType::kChoice:
    case ParamType::kText:
      return std::holds_alternative<std::string>(v);
    case ParamType::kNumbers:
      return std::holds_alternative<std::vector<double>>(v);
    case ParamType::kIntegers:
      return std::holds_alternative<std::vector<int64_t>>(v);
    case ParamType::kChoices:
      return std::holds_alternative<std::vector<std::string>>(v);
  }
  return false;
}

// Integers given where numbers are expected (a proto int64 into a number row, JSON 5 into
// a list of numbers) are taken as they are.
ParamValue Widen(const ParamSpec& s, ParamValue v) {
  if (s.type == ParamType::kNumber && std::holds_alternative<int64_t>(v)) {
    return static_cast<double>(std::get<int64_t>(v));
  }
  if (s.type == ParamType::kNumbers && std::holds_alternative<std::vector<int64_t>>(v)) {
    const auto& i = std::get<std::vector<int64_t>>(v);
    return std::vector<double>(i.begin(), i.end());
  }
  return v;
}

// "" when `v` (of the row's type) is allowed, else why not.
std::string Violation(const ParamRow& row, const ParamValue& v) {
  const ParamSpec& s = row.spec;
  auto in_range = [&](double x) { return std::isfinite(x) && s.range.Contains(x); };
  auto list_size_ok = [&](size_t n) {
    if (s.count > 0) return n == static_cast<size_t>(s.count);
    return n > 0 || s.allow_empty;
  };
  switch (s.type) {
    case ParamType::kBool:
    case ParamType::kText:
      break;
    case ParamType::kInteger:
      if (!in_range(static_cast<double>(std::get<int64_t>(v)))) return Expected(s);
      break;
    case ParamType::kNumber:
      if (!in_range(std::get<double>(v))) return Expected(s);
      break;
    case ParamType::kChoice:
      if (std::find(s.choices.begin(), s.choices.end(), std::get<std::string>(v)) ==
          s.choices.end())
        return Expected(s);
      break;
    case ParamType::kNumbers: {
      const auto& x = std::get<std::vector<double>>(v);
      if (!list_size_ok(x.size()) || !std::all_of(x.begin(), x.end(), in_range)) return Expected(s);
      break;
    }
    case ParamType::kIntegers: {
      const auto& x = std::get<std::vector<int64_t>>(v);
      if (!list_size_ok(x.size()) ||
          !std::all_of(x.begin(), x.end(), [&](int64_t i) { return in_range(double(i)); }))
        return Expected(s);
      break;
    }
    case ParamType::kChoices: {
      const auto& x = std::get<std::vector<std::string>>(v);
      if (!list_size_ok(x.size())) return Expected(s);
      for (const std::string& c : x) {
        if (std::find(s.choices.begin(), s.choices.end(), c) == s.choices.end()) return Expected(s);
      }
      break;
    }
  }
  return row.check ? row.check(v) : "";
}

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
  const RadiusSearchOptions& rs = o.radius_search;
  if (rs.max_radius_voxels != 0 && rs.max_radius_voxels < rs.min_radius_voxels) {
    return Broken{
        "radius_search.r_max", absl::StrCat(rs.max_radius_voxels),
        absl::StrCat("must be 0 or at least radius_search.r_min = ", rs.min_radius_voxels)};
  }
  return std::nullopt;
}

// Settings that follow another unless set: detect.scvd_r and recover.scvd_r of 0 take
// separate.r.
void ResolveFollowers(PipelineOptions& o) {
  ExtractionOptions& x = o.extraction;
  for (ExtendOptions* e : {&x.detect_extend, &x.recover_extend}) {
    if (e->scvd_radius_voxels == 0) e->scvd_radius_voxels = x.separation.radius_voxels;
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

nlohmann::json ToJson(const ParamValue& value) {
  return std::visit([](const auto& x) { return Json(x); }, value);
}

ParamRange ParamRange::Parse(absl::string_view text) {
  ParamRange r;
  r.text = std::string(text);
  absl::string_view t = absl::StripAsciiWhitespace(text);
  if (absl::ConsumePrefix(&t, "0 |")) {
    r.zero_too = true;
    t = absl::StripAsciiWhitespace(t);
  }
  assert(t.size() >= 5 && (t.front() == '(' || t.front() == '[') &&
         (t.back() == ')' || t.back() == ']'));
  r.lo_open = t.front() == '(';
  r.hi_open = t.back() == ')';
  const std::vector<std::string> parts =
      absl::StrSplit(t.substr(1, t.size() - 2), ',', absl::SkipWhitespace());
  assert(parts.size() == 2);
  [[maybe_unused]] const bool ok = parts.size() == 2 &&
                                   absl::SimpleAtod(absl::StripAsciiWhitespace(parts[0]), &r.lo) &&
                                   absl::SimpleAtod(absl::StripAsciiWhitespace(parts[1]), &r.hi);
  assert(ok && r.lo <= r.hi);
  return r;
}

bool ParamRange::Contains(double v) const {
  if (zero_too && v == 0) return true;
  const bool above = lo_open ? v > lo : v >= lo;
  const bool below = hi_open ? v < hi : v <= hi;
  return above && below;
}

std::string ParamSpec::name() const {
  absl::string_view k = key;
  absl::ConsumePrefix(&k, "input.");
  return absl::StrReplaceAll(k, {{".", "_"}});
}

std::string ParamSpec::Describe() const {
  std::string d = TypeName(type);
  if (type == ParamType::kChoice || type == ParamType::kChoices) {
    absl::StrAppend(&d, " ", absl::StrJoin(choices, ", "));
  } else if (type != ParamType::kBool && type != ParamType::kText) {
    if (count > 0) d = absl::StrCat(count, " ", d);
    absl::StrAppend(&d, " in ", range.text);
  }
  if (!unit.empty()) absl::StrAppend(&d, ", ", unit);
  return d;
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
  assert(i < ParamRows().size());
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

absl::StatusOr<ParamValue> ParseParameterText(const ParamSpec& s, absl::string_view text,
                                              absl::string_view display) {
  auto bad = [&]() {
    return absl::InvalidArgumentError(absl::StrCat(display, "=", text, " ", Expected(s)));
  };
  auto number = [](absl::string_view t, double* out) {
    return absl::SimpleAtod(absl::StripAsciiWhitespace(t), out);
  };
  auto integer = [&](absl::string_view t, int64_t* out) {
    if (absl::SimpleAtoi(absl::StripAsciiWhitespace(t), out)) return true;
    double d = 0;
    if (!number(t, &d) || d != std::floor(d) || std::abs(d) > 9.2e18) return false;
    *out = static_cast<int64_t>(d);
    return true;
  };
  switch (s.type) {
    case ParamType::kBool: {
      const std::string t = absl::AsciiStrToLower(text);
      if (t == "true" || t == "1" || t == "yes") return ParamValue(true);
      if (t == "false" || t == "0" || t == "no") return ParamValue(false);
      return bad();
    }
    case ParamType::kInteger: {
      int64_t i = 0;
      if (!integer(text, &i)) return bad();
      return ParamValue(i);
    }
    case ParamType::kNumber: {
      double d = 0;
      if (!number(text, &d)) return bad();
      return ParamValue(d);
    }
    case ParamType::kChoice:
    case ParamType::kText:
      return ParamValue(std::string(text));
    case ParamType::kNumbers: {
      // input.window is written LO:HI.
      const char sep = s.count == 2 && absl::StrContains(text, ':') ? ':' : ',';
      std::vector<double> out;
      for (absl::string_view p : absl::StrSplit(text, sep, absl::SkipEmpty())) {
        double d = 0;
        if (!number(p, &d)) return bad();
        out.push_back(d);
      }
      return ParamValue(out);
    }
    case ParamType::kIntegers: {
      // input.dims is written NXxNYxNZ.
      const char sep = absl::StrContains(text, 'x') ? 'x' : ',';
      std::vector<int64_t> out;
      for (absl::string_view p : absl::StrSplit(text, sep, absl::SkipEmpty())) {
        int64_t i = 0;
        if (!integer(p, &i)) return bad();
        out.push_back(i);
      }
      return ParamValue(out);
    }
    case ParamType::kChoices: {
      std::vector<std::string> out;
      for (absl::string_view p : absl::StrSplit(text, ',', absl::SkipEmpty())) {
        out.emplace_back(absl::StripAsciiWhitespace(p));
      }
      return ParamValue(out);
    }
  }
  return bad();
}

std::string ParameterValueJson(const ParamValue& value) { return Show(value); }

absl::Status ParameterBuilder::Check(const ParamSpec& spec, const ParamValue& value,
                                     const std::string& display) const {
  if (spec.scope == ParamScope::kLocal && scope_ == ParamScope::kJob) {
    return absl::InvalidArgumentError(absl::StrCat(
        display, " (", spec.key,
        ") names a path or program of the machine that runs the pipeline; a job may not set "
        "it"));
  }
  if (!HasType(spec, value)) return Bad(display, Show(value), Expected(spec));
  const std::string why = Violation(RowOf(spec), value);
  if (!why.empty()) return Bad(display, Show(value), why);
  return absl::OkStatus();
}

absl::Status ParameterBuilder::Add(const ParamSpec& spec, ParamValue value, std::string display) {
  value = Widen(spec, std::move(value));
  SM_RETURN_IF_ERROR(Check(spec, value, display));
  entries_.push_back({&spec, std::move(value), std::move(display), source_});
  return absl::OkStatus();
}

absl::Status ParameterBuilder::AddJson(absl::string_view text, absl::string_view source) {
  Json root;
  try {
    root = Json::parse(text.begin(), text.end());
  } catch (const Json::parse_error& e) {
    return absl::InvalidArgumentError(absl::StrCat(source, ": not valid JSON: ", e.what()));
  }
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
        if (!value) return Bad(display, JsonText(v), Expected(*spec));
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
    return Bad(display, b->value, b->why);
  }
  return o;
}

absl::Status CheckParameters(const PipelineOptions& options) {
  for (const ParamRow& row : ParamRows()) {
    std::optional<ParamValue> v = row.get(options);
    if (!v) continue;
    const std::string why = Violation(row, *v);
    if (!why.empty()) return Bad(absl::StrCat("parameter ", row.spec.key), Show(*v), why);
  }
  if (std::optional<Broken> b = BrokenRelation(options)) {
    return Bad(absl::StrCat("parameter ", b->key), b->value, b->why);
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
    std::string shown = d ? Show(*d) : "unset";
    if (s.preset) shown = "\"extended\"";
    absl::StrAppend(&md, "| `", s.key, "` | `--", s.name(), "` | ", s.Describe(), " | `", shown,
                    "` | ", s.doc, s.scope == ParamScope::kLocal ? " (offline only)" : "", " |\n");
  }
  return md;
}

}  // namespace sheetmesh
