// Excerpt: text from a file or a third-party library, fit for an error message — at most
// `max` bytes, unprintable bytes as '?', and how long it was when it had to be cut. A damaged
// file can make a library quote gigabytes of its garbage back in an exception.
#ifndef SHEETMESH_COMMON_EXCERPT_H_
#define SHEETMESH_COMMON_EXCERPT_H_

#include <cstddef>
#include <string>
#include <string_view>

namespace sheetmesh {

inline std::string Excerpt(std::string_view text, size_t max = 240) {
  std::string out(text.substr(0, max));
  for (char& c : out) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  }
  if (text.size() > max) out += "... (" + std::to_string(text.size()) + " bytes)";
  return out;
}

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_EXCERPT_H_
