// The parameter values: their JSON and text forms, and the checks of type and range.
#include <cmath>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "common/assert.h"
#include "common/json_text.h"
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

}  // namespace

// "5", "true", "\"paper\"", "[2,3,4]".
std::string ShowValue(const ParamValue& v) {
  // JSON has no text for a number beyond a double or not a number: say what it was.
  if (const double* d = std::get_if<double>(&v); d != nullptr && !std::isfinite(*d)) {
    return std::isnan(*d) ? "nan" : *d > 0 ? "inf (beyond a double's range)"
                                           : "-inf (beyond a double's range)";
  }
  // A long list is shown by its head and its length, not quoted whole in a message.
  const Json j = ToJson(v);
  if (j.is_array() && j.size() > 12) {
    std::vector<std::string> head;
    for (size_t i = 0; i < 6; ++i) head.push_back(JsonText(j[i]));
    return absl::StrCat("[", absl::StrJoin(head, ","), ", ... (", j.size(), " items)]");
  }
  return JsonText(j);
}

absl::Status BadValue(const std::string& display, const std::string& value, absl::string_view why) {
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
  return absl::StrCat("must be a ", s.allow_empty ? "" : "non-empty ", "list of at most ",
                      s.max_count, " ", what);
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
  // An integer beyond 2^53 may round onto a bound (2^53 + 1 onto 2^53): it is in range only
  // when the doubles on both sides of its rounding are.
  auto int_in_range = [&](int64_t i) {
    const double d = static_cast<double>(i);
    if (!in_range(d)) return false;
    if (static_cast<long double>(i) == static_cast<long double>(d)) return true;
    return in_range(std::nextafter(d, -HUGE_VAL)) && in_range(std::nextafter(d, HUGE_VAL));
  };
  auto list_size_ok = [&](size_t n) {
    if (s.count > 0) return n == static_cast<size_t>(s.count);
    return (n > 0 || s.allow_empty) && n <= static_cast<size_t>(s.max_count);
  };
  switch (s.type) {
    case ParamType::kBool:
    case ParamType::kText:
      break;
    case ParamType::kInteger:
      if (!int_in_range(std::get<int64_t>(v))) return Expected(s);
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
      if (!list_size_ok(x.size()) || !std::all_of(x.begin(), x.end(), int_in_range))
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
  SM_ASSERT(t.size() >= 5 && (t.front() == '(' || t.front() == '[') &&
            (t.back() == ')' || t.back() == ']'));
  r.lo_open = t.front() == '(';
  r.hi_open = t.back() == ')';
  const std::vector<std::string> parts =
      absl::StrSplit(t.substr(1, t.size() - 2), ',', absl::SkipWhitespace());
  SM_ASSERT(parts.size() == 2);
  [[maybe_unused]] const bool ok = parts.size() == 2 &&
                                   absl::SimpleAtod(absl::StripAsciiWhitespace(parts[0]), &r.lo) &&
                                   absl::SimpleAtod(absl::StripAsciiWhitespace(parts[1]), &r.hi);
  SM_ASSERT(ok && r.lo <= r.hi);
  return r;
}

bool ParamRange::Contains(double v) const {
  if (zero_too && v == 0) return true;
  const bool above = lo_open ? v > lo : v >= lo;
  const bool below = hi_open ? v < hi : v <= hi;
  return above && below;
}

std::string ParamSpec::Describe() const {
  std::string d = TypeName(type);
  if (type == ParamType::kChoice || type == ParamType::kChoices) {
    absl::StrAppend(&d, " ", absl::StrJoin(choices, ", "));
  } else if (type != ParamType::kBool && type != ParamType::kText) {
    if (count > 0) d = absl::StrCat(count, " ", d);
    absl::StrAppend(&d, " in ", range.text);
  }
  const bool list = type == ParamType::kNumbers || type == ParamType::kIntegers ||
                    type == ParamType::kChoices;
  if (list && count == 0) absl::StrAppend(&d, ", up to ", max_count);
  if (!unit.empty()) absl::StrAppend(&d, ", ", unit);
  return d;
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

std::string ParameterValueJson(const ParamValue& value) { return ShowValue(value); }

}  // namespace sheetmesh
