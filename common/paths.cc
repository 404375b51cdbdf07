#include "common/paths.h"

#include <limits.h>
#include <stdlib.h>

#include <cerrno>
#include <filesystem>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "common/file_util.h"

namespace sheetmesh {

absl::StatusOr<std::string> ResolveUnderRoots(const std::string& path,
                                              const std::vector<std::string>& roots,
                                              absl::string_view what) {
  if (path.find('\0') != std::string::npos) {
    return absl::InvalidArgumentError(
        absl::StrCat(what, " holds a NUL byte (after '", path.c_str(), "')"));
  }
  if (roots.empty()) {
    return absl::PermissionDeniedError(
        absl::StrCat(what, " '", path, "': no folder may be read here (no allowed root)"));
  }
  if (path.empty() || path[0] != '/') {
    return absl::InvalidArgumentError(absl::StrCat(what, " '", path, "' must be absolute"));
  }
  for (const auto& part : std::filesystem::path(path)) {
    if (part == "..") {
      return absl::PermissionDeniedError(absl::StrCat(what, " '", path, "' may not contain '..'"));
    }
  }
  auto under_a_root = [&](const std::string& p) {
    for (const std::string& root : roots) {
      char rr[PATH_MAX];
      if (::realpath(root.c_str(), rr) == nullptr) continue;
      std::string r = rr;
      if (r.back() != '/') r += '/';
      if (p.rfind(r, 0) == 0 || p + "/" == r) return true;
    }
    return false;
  };
  char real[PATH_MAX];
  if (::realpath(path.c_str(), real) == nullptr) {
    // Whether a file outside the roots exists is not for the caller to learn.
    const int err = errno;
    if (!under_a_root(std::filesystem::path(path).lexically_normal().string())) {
      return absl::PermissionDeniedError(absl::StrCat(
          what, " '", path, "' is outside the allowed roots (", absl::StrJoin(roots, ", "), ")"));
    }
    return ErrnoStatus(err, path);
  }
  const std::string resolved = real;
  if (under_a_root(resolved)) return resolved;
  return absl::PermissionDeniedError(absl::StrCat(what, " '", path, "' resolves to '", resolved,
                                                  "', outside the allowed roots (",
                                                  absl::StrJoin(roots, ", "), ")"));
}

}  // namespace sheetmesh
