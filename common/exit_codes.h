// The exit code of a command that failed: one table for every program.
#ifndef SHEETMESH_COMMON_EXIT_CODES_H_
#define SHEETMESH_COMMON_EXIT_CODES_H_

#include "absl/status/status.h"

namespace sheetmesh {

// 2 when the user can mend the input or the parameters, 1 for the rest (the machine, the
// network, a bug). kInvalidArgument, kOutOfRange and kDataLoss (a bad or cut file) are
// always the input's; kResourceExhausted (too big for the budget), kFailedPrecondition,
// kPermissionDenied and kNotFound are when `about_user_input`: for the offline CLI, whose
// files are the user's, always; for a client of the service, when the status is about a
// job that failed on its volume or a file of the user's, not about the server's own state.
inline int ExitCodeOf(const absl::Status& status, bool about_user_input) {
  switch (status.code()) {
    case absl::StatusCode::kOk:
      return 0;
    case absl::StatusCode::kInvalidArgument:
    case absl::StatusCode::kOutOfRange:
    case absl::StatusCode::kDataLoss:
      return 2;
    case absl::StatusCode::kResourceExhausted:
    case absl::StatusCode::kFailedPrecondition:
    case absl::StatusCode::kPermissionDenied:
    case absl::StatusCode::kNotFound:
      return about_user_input ? 2 : 1;
    default:
      return 1;
  }
}

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_EXIT_CODES_H_
