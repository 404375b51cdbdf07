// JSON as text that never throws: bytes that are not UTF-8 (a file name from a Latin-1
// file system, a flag's text) are written as U+FFFD instead of making nlohmann::json
// throw, which in a worker thread would end the whole server.
#ifndef SHEETMESH_COMMON_JSON_TEXT_H_
#define SHEETMESH_COMMON_JSON_TEXT_H_

#include <nlohmann/json.hpp>
#include <string>

namespace sheetmesh {

// `j` as text; `indent` < 0: one line.
inline std::string JsonText(const nlohmann::json& j, int indent = -1) {
  return j.dump(indent, ' ', /*ensure_ascii=*/false, nlohmann::json::error_handler_t::replace);
}

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_JSON_TEXT_H_
