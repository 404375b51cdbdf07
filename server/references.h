// References: volumes named by path. Only paths under the configured allowed roots can be
// read — after following symbolic links, so that neither ".." nor a link leaves them.
#ifndef SHEETMESH_SERVER_REFERENCES_H_
#define SHEETMESH_SERVER_REFERENCES_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace sheetmesh::server {

// The real path of `path` when it lies under one of `roots`. kPermissionDenied naming the
// request's field (`field`: "volume_path" in a job's input, "path" in the volume calls) and
// the path when it does not (or when no root is configured); kNotFound when it does not
// exist.
absl::StatusOr<std::string> ResolveReference(const std::string& path,
                                             const std::vector<std::string>& roots,
                                             const char* field = "volume_path");

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_REFERENCES_H_
