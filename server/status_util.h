// The one place absl::Status becomes grpc::Status, with long messages cut.
#ifndef SHEETMESH_SERVER_STATUS_UTIL_H_
#define SHEETMESH_SERVER_STATUS_UTIL_H_

#include <grpcpp/support/status.h>

#include "absl/status/status.h"

namespace sheetmesh::server {

// The same code and message; messages beyond 4 KiB are cut, saying so.
grpc::Status ToGrpcStatus(const absl::Status& status);

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_STATUS_UTIL_H_
