// Internal to the parameter table (parameters.cc, parameter_table.cc): each row's spec and
// how it reads and writes its member of PipelineOptions.
#ifndef SHEETMESH_WORKER_PIPELINE_RUN_PARAMETER_ROWS_H_
#define SHEETMESH_WORKER_PIPELINE_RUN_PARAMETER_ROWS_H_

#include <functional>
#include <optional>
#include <vector>

#include "worker/pipeline/run/parameters.h"

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

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_RUN_PARAMETER_ROWS_H_
