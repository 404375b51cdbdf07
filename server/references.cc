#include "server/references.h"

#include "absl/strings/str_cat.h"
#include "common/paths.h"

namespace sheetmesh::server {

absl::StatusOr<std::string> ResolveReference(const std::string& path,
                                             const std::vector<std::string>& roots,
                                             const char* field) {
  if (roots.empty()) {
    return absl::PermissionDeniedError(absl::StrCat(
        field, " '", path, "': this server reads no paths (no --allowed_root configured)"));
  }
  return ResolveUnderRoots(path, roots, field);
}

}  // namespace sheetmesh::server
