#include "worker/pipeline/cli/parameter_flags.h"

#include <cstring>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_replace.h"
#include "common/status_macros.h"

namespace sheetmesh {

absl::StatusOr<ParameterFlags> TakeParameterFlags(
    int argc, char** argv, const std::function<bool(const ParamSpec&)>& accepts,
    absl::string_view command) {
  ParameterFlags out;
  out.rest.push_back(argv[0]);
  for (int i = 1; i < argc; ++i) {
    const absl::string_view a = argv[i];
    if (a == "--") {
      for (; i < argc; ++i) out.rest.push_back(argv[i]);
      break;
    }
    if (a.size() < 2 || a[0] != '-') {
      out.rest.push_back(argv[i]);
      continue;
    }
    absl::string_view body = a.substr(a[1] == '-' ? 2 : 1);
    const size_t eq = body.find('=');
    const absl::string_view name = body.substr(0, eq);
    const bool has_value = eq != absl::string_view::npos;
    const ParamSpec* spec = FindParameter(name);
    bool negated = false;
    if (spec == nullptr && absl::StartsWith(name, "no")) {
      const ParamSpec* s = FindParameter(name.substr(2));
      if (s != nullptr && s->type == ParamType::kBool) {
        spec = s;
        negated = true;
      }
    }
    if (spec == nullptr) {
      if (const char* now = RenamedParameter(name)) {
        const ParamSpec* n = FindParameter(now);
        return absl::InvalidArgumentError(absl::StrCat(
            "--", name, " is now ", n ? absl::StrCat("--", n->name()) : std::string(now),
            " (sheetmesh 0.9 gave every setting one name; sheetmesh-pipeline --help lists "
            "them)"));
      }
      out.rest.push_back(argv[i]);  // one of the command's own flags, or a mistake for absl
      continue;
    }
    const std::string display = absl::StrCat("--", spec->name());
    if (!accepts(*spec)) {
      return absl::InvalidArgumentError(
          absl::StrCat(display, " (", spec->key, ") is not used by '", command, "'"));
    }
    std::string text;
    if (negated) {
      if (has_value) {
        return absl::InvalidArgumentError(
            absl::StrCat("--", name, " takes no value; write ", display, "=false"));
      }
      text = "false";
    } else if (has_value) {
      text = std::string(body.substr(eq + 1));
    } else if (spec->type == ParamType::kBool) {
      text = "true";
    } else if (i + 1 < argc) {
      text = argv[++i];
    } else {
      return absl::InvalidArgumentError(absl::StrCat(display, " needs a value"));
    }
    SM_ASSIGN_OR_RETURN(ParamValue v, ParseParameterText(*spec, text, display));
    SM_RETURN_IF_ERROR(out.given.Add(*spec, std::move(v), display));
    out.keys.push_back(spec->key);
  }
  return out;
}

std::string ParameterFlagsHelp(const std::function<bool(const ParamSpec&)>& accepts) {
  const PipelineOptions defaults;
  std::string help;
  for (const ParamSpec& s : Parameters()) {
    if (!accepts(s)) continue;
    const std::optional<ParamValue> d = GetParameter(s, defaults);
    std::string shown = d ? ParameterValueJson(*d) : "unset";
    if (s.preset) shown = "\"extended\"";
    absl::StrAppend(&help, "  --", s.name(), " (", s.key, ")  ", s.Describe(), "; default ", shown,
                    "\n      ", s.doc, "\n");
  }
  return help;
}

}  // namespace sheetmesh
