#include "server/references.h"

#include <limits.h>
#include <stdlib.h>

#include <filesystem>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "common/file_util.h"

namespace sheetmesh::server {

absl::StatusOr<std::string> ResolveReference(const std::string& path,
                                             const std::vector<std::string>& roots) {
  if (roots.empty()) {
    return absl::PermissionDeniedError(absl::StrCat(
        "volume_path '", path, "': this server reads no paths (no --allowed_root configured)"));
  }
  if (path.empty() || path[0] != '/') {
    return absl::InvalidArgumentError(absl::StrCat("volume_path '", path, "' must be absolute"));
  }
  for (const auto& part : std::filesystem::path(path)) {
    if (part == "..") {
      return absl::PermissionDeniedError(
          absl::StrCat("volume_path '", path, "' may not contain '..'"));
    }
  }
  char real[PATH_MAX];
  if (::realpath(path.c_str(), real) == nullptr) return ErrnoStatus(errno, path);
  const std::string resolved = real;
  for (const std::string& root : roots) {
    char rr[PATH_MAX];
    if (::realpath(root.c_str(), rr) == nullptr) continue;
    std::string r = rr;
    if (r.back() != '/') r += '/';
    if (resolved.rfind(r, 0) == 0 || resolved + "/" == r) return resolved;
  }
  return absl::PermissionDeniedError(absl::StrCat("volume_path '", path, "' resolves to '",
                                                  resolved, "', outside the allowed roots (",
                                                  absl::StrJoin(roots, ", "), ")"));
}

}  // namespace sheetmesh::server
