// The pipeline's parameters as one table: every setting of PipelineOptions under one name,
// with its type, range, unit and a line of documentation. The JSON config reader, the
// command-line flags, the service's proto mapping, the report, docs/parameters.md
// and the error messages all walk this table, so a setting is spelt one way everywhere:
// the key path `separate.r` in a config file and the report, `--separate_r` (or
// `--separate.r`) on a command line, `separate_r` in the proto. Keys of the `input` group
// drop the group in their flag and proto names (`input.labels` is `--labels`).
#ifndef SHEETMESH_WORKER_PIPELINE_RUN_PARAMETERS_H_
#define SHEETMESH_WORKER_PIPELINE_RUN_PARAMETERS_H_

#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "worker/pipeline/run/parameter_types.h"
#include "worker/pipeline/run/pipeline_options.h"

namespace sheetmesh {

// Every parameter, in the order of the workflow (input, extraction, surface, similarity,
// volume mesh, output).
const std::vector<ParamSpec>& Parameters();

// The parameter called `name` — its key ("separate.r"), or its flag/proto name
// ("separate_r"), with '-' read as '_' — or null.
const ParamSpec* FindParameter(absl::string_view name);

// The new name of a parameter key or flag that an earlier version spelt otherwise
// ("r_sep" -> "separate.r"), or null.
const char* RenamedParameter(absl::string_view old_name);

// The value of `spec` in `options`, or nullopt where the setting is unset (an optional
// input override such as input.spacing) or is a preset.
std::optional<ParamValue> GetParameter(const ParamSpec& spec, const PipelineOptions& options);

// Parses command-line text for `spec`: "true"/"false", a number, "2,3,4" for lists,
// "64x64x32" or "64,64,32" for input.dims and "LO:HI" for input.window. kInvalidArgument
// naming `display` (e.g. "--separate_r") and the text. The value is not range-checked.
absl::StatusOr<ParamValue> ParseParameterText(const ParamSpec& spec, absl::string_view text,
                                              absl::string_view display);

// The value as a config file writes it: 5, true, "paper", [2, 3, 4].
std::string ParameterValueJson(const ParamValue& value);

// Collects settings from any number of sources, checking each (type, range, choices,
// scope) as it comes, and applies them in order on Build: presets first, then every other
// setting as it came (a later source overrides an earlier one). Not thread-safe.
class ParameterBuilder {
 public:
  // `scope` kJob refuses kLocal parameters (naming them); the default takes every one.
  ParameterBuilder() = default;
  explicit ParameterBuilder(ParamScope scope) : scope_(scope) {}

  // A config document: nested objects by key path ({"separate": {"r": 5}}), a key may
  // also be a whole path ({"separate.r": 5}). kInvalidArgument naming `source`, the key
  // path and the value for malformed JSON, an unknown or renamed key, a wrong type or a
  // value out of range.
  absl::Status AddJson(absl::string_view text, absl::string_view source);

  // One setting; `display` names it in errors as the caller knows it ("--separate_r",
  // "parameters.separate_r"). Settings added one by one between two documents are one
  // source. kInvalidArgument as for AddJson.
  absl::Status Add(const ParamSpec& spec, ParamValue value, std::string display);

  // `base` with every setting applied, then the settings that follow others resolved
  // (detect.scvd_r and recover.scvd_r of 0 take separate.r). kInvalidArgument for settings that
  // disagree (improve.insert_below_degrees above improve.target_degrees, two settings of
  // one exclusive group from one source).
  absl::StatusOr<PipelineOptions> Build(PipelineOptions base = {}) const;

  bool empty() const { return entries_.empty(); }

 private:
  struct Entry {
    const ParamSpec* spec;
    ParamValue value;
    std::string display;
    int source;
  };
  absl::Status Check(const ParamSpec& spec, const ParamValue& value,
                     const std::string& display) const;

  ParamScope scope_ = ParamScope::kLocal;
  std::vector<Entry> entries_;
  int source_ = 0;
};

// Checks every parameter of `options` against its range and the relations between them.
// kInvalidArgument naming the key and value ("parameter separate.r = -1 must be in (0,
// 1000]").
absl::Status CheckParameters(const PipelineOptions& options);

// Every parameter of `options` as a config document, keys sorted, presets and unset
// settings left out: the same settings always give the same text. With
// `include_local` false, kLocal parameters are left out (a job's form).
std::string CanonicalParametersJson(const PipelineOptions& options, bool include_local);

// docs/parameters.md's table (markdown): key, flag, type and range, default, doc.
std::string ParametersMarkdown();

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_RUN_PARAMETERS_H_
