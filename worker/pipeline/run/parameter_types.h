// The parameter table's vocabulary (parameters.h walks the table): a value as a source
// gives it, its type, who may set it, its range and its spec. Apart so that the table's
// internal rows (parameter_rows.h) and its JSON form (parameters_json.h) need only these.
#ifndef SHEETMESH_WORKER_PIPELINE_RUN_PARAMETER_TYPES_H_
#define SHEETMESH_WORKER_PIPELINE_RUN_PARAMETER_TYPES_H_

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "absl/strings/string_view.h"

namespace sheetmesh {

// A value as a source gives it: a config file, a flag, a proto field.
using ParamValue = std::variant<bool, int64_t, double, std::string, std::vector<double>,
                                std::vector<int64_t>, std::vector<std::string>>;

enum class ParamType {
  kBool,
  kInteger,   // int64_t
  kNumber,    // double
  kChoice,    // std::string, one of `choices`
  kText,      // std::string
  kNumbers,   // std::vector<double>
  kIntegers,  // std::vector<int64_t>
  kChoices,   // std::vector<std::string>, each one of `choices`
};

// Who may set a parameter. Paths and programs of the machine running the pipeline are for
// its own user only: a job sent to the service may not name them.
enum class ParamScope { kJob, kLocal };

// An interval of allowed values, written as in mathematics: "(0, 180]", "[1, 64]"; "0 |
// [0.25, 8]" also allows 0, which then means "none" or "automatic" (the doc line says).
struct ParamRange {
  double lo = 0, hi = 0;
  bool lo_open = false, hi_open = false;
  bool zero_too = false;
  std::string text;  // as written

  // REQUIRES: `text` is well formed (the table's own strings; checked by the tests).
  static ParamRange Parse(absl::string_view text);
  bool Contains(double v) const;
};

struct ParamSpec {
  std::string key;  // "separate.r": the name, as a key path of the config JSON
  ParamType type = ParamType::kNumber;
  ParamRange range;                  // numbers and integers, and each item of a list
  int count = 0;                     // lists: exactly this many items (0: up to max_count)
  int max_count = 16;                // lists: at most this many items (a long list runs long)
  bool allow_empty = false;          // lists: the empty list is allowed
  std::vector<std::string> choices;  // kChoice, kChoices
  std::string unit;                  // "voxels", "degrees", "" when none
  std::string doc;                   // one line
  ParamScope scope = ParamScope::kJob;
  // Rows of one non-empty group may not both be set by one source (labels and window).
  std::string exclusive;
  // A preset sets other rows; it is applied before every other row of every source, so
  // that a row set anywhere beats the preset (surface.method).
  bool preset = false;

  // The flag and proto field name: "separate_r"; "labels" for "input.labels".
  std::string name() const;
  // "number in (0, 1000], voxels", for help texts.
  std::string Describe() const;
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_RUN_PARAMETER_TYPES_H_
