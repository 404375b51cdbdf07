// JSON parsed without exceptions: a document that does not parse — bad syntax, or a number
// beyond a double's range ("r": 1e999, which nlohmann::json reports as out_of_range, not as
// a parse error) — is kInvalidArgument naming the key path where it stopped.
#ifndef SHEETMESH_COMMON_JSON_PARSE_H_
#define SHEETMESH_COMMON_JSON_PARSE_H_

#include <nlohmann/json.hpp>
#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace sheetmesh {

// `text` parsed. kInvalidArgument naming `source`, the key path ("surface.r", "scales[3]")
// and the text there when it does not parse: "config.json: 'r' = 1e999 is beyond the range
// of a number (at most 1.8e308)". Never throws.
absl::StatusOr<nlohmann::json> ParseJson(absl::string_view text, absl::string_view source);

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_JSON_PARSE_H_
