#include "server/references.h"

#include "absl/strings/str_cat.h"
#include "common/paths.h"
#include "common/status_macros.h"
#include "worker/pipeline/volume/hdf5_io.h"

namespace sheetmesh::server {

absl::StatusOr<std::string> ResolveReference(const std::string& path,
                                             const std::vector<std::string>& roots,
                                             const char* field) {
  if (roots.empty()) {
    return absl::PermissionDeniedError(absl::StrCat(
        field, " '", path, "': this server reads no paths (no --allowed_root configured)"));
  }
  // "scan.h5:/entry/data": the file is checked; the dataset inside it is kept.
  if (const auto hdf5 = SplitHdf5Path(path)) {
    SM_ASSIGN_OR_RETURN(std::string file, ResolveUnderRoots(hdf5->first, roots, field));
    return absl::StrCat(file, ":", hdf5->second);
  }
  return ResolveUnderRoots(path, roots, field);
}

}  // namespace sheetmesh::server
