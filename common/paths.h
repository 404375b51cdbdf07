// Paths under allowed roots: a path given from outside (a job's volume_path, the data file
// a detached NRRD header names) may be read only when it lies under one of the roots after
// following symbolic links, so that neither ".." nor a link leaves them.
#ifndef SHEETMESH_COMMON_PATHS_H_
#define SHEETMESH_COMMON_PATHS_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace sheetmesh {

// The real path of `path` when it lies under one of `roots`. `what` names the path in
// messages ("volume_path", "x.nhdr: data file"). kInvalidArgument for a relative path or one
// holding a NUL byte; kPermissionDenied naming the path when it is outside every root, holds
// "..", or `roots` is empty; the errno's code (kNotFound, ...) when it cannot be resolved.
absl::StatusOr<std::string> ResolveUnderRoots(const std::string& path,
                                              const std::vector<std::string>& roots,
                                              absl::string_view what);

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_PATHS_H_
