// Internal to the parameter table (parameters.cc, parameter_table.cc): each row's spec and
// how it reads and writes its member of PipelineOptions.
#ifndef SHEETMESH_WORKER_PIPELINE_RUN_PARAMETER_ROWS_H_
#define SHEETMESH_WORKER_PIPELINE_RUN_PARAMETER_ROWS_H_

#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <vector>

#include "worker/pipeline/run/parameter_types.h"
#include "worker/pipeline/run/pipeline_options.h"

namespace sheetmesh {

struct ParamRow {
  ParamSpec spec;
  // The member's value; nullopt where it is unset (or for presets).
  std::function<std::optional<ParamValue>(const PipelineOptions&)> get;
  // Sets the member. REQUIRES: `value` has the row's type and passed its checks.
  std::function<void(const ParamValue&, PipelineOptions&)> set;
  // A check beyond type and range: "" when `value` is fine, else why not ("must be [lo,
  // hi] with lo <= hi"). Null: none.
  std::function<std::string(const ParamValue&)> check;
};

// The table, built once. Thread-safe.
const std::vector<ParamRow>& ParamRows();

// The row whose spec is `spec`. REQUIRES: `spec` is an element of Parameters().
const ParamRow& RowOf(const ParamSpec& spec);

// Old spellings of keys and flags, for the error that names the new one.
struct Renamed {
  const char* old_name;
  const char* new_key;
};
const std::vector<Renamed>& RenamedParameters();

// Shared by the parameter files (parameter_values.cc defines them).

// The value as JSON text: 5, true, "paper", [2,3,4].
std::string ShowValue(const ParamValue& v);
// kInvalidArgument "DISPLAY = VALUE WHY".
absl::Status BadValue(const std::string& display, const std::string& value, absl::string_view why);
// What a value of `s` must be ("must be a number in (0, 1000]").
std::string Expected(const ParamSpec& s);
// The JSON value as `s`'s type, or nullopt when it is not of that type.
std::optional<ParamValue> FromJson(const ParamSpec& s, const nlohmann::json& v);
// Whether `v` holds `s`'s type.
bool HasType(const ParamSpec& s, const ParamValue& v);
// Integers where numbers are expected, taken as numbers.
ParamValue Widen(const ParamSpec& s, ParamValue v);
// "" when `v` (of the row's type) is allowed, else why not.
std::string Violation(const ParamRow& row, const ParamValue& v);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_RUN_PARAMETER_ROWS_H_
