#include "server/status_util.h"

#include <string>

#include "absl/strings/str_cat.h"

namespace sheetmesh::server {

grpc::Status ToGrpcStatus(const absl::Status& status) {
  if (status.ok()) return grpc::Status::OK;
  constexpr size_t kMax = 4096;
  std::string msg(status.message());
  if (msg.size() > kMax)
    msg = absl::StrCat(msg.substr(0, kMax), "... (", msg.size() - kMax, " more bytes)");
  return grpc::Status(static_cast<grpc::StatusCode>(status.code()), msg);
}

}  // namespace sheetmesh::server
