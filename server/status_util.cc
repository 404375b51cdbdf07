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

absl::Status FromGrpcStatus(const grpc::Status& status) {
  if (status.ok()) return absl::OkStatus();
  return absl::Status(static_cast<absl::StatusCode>(status.error_code()), status.error_message());
}

}  // namespace sheetmesh::server
