// Status propagation macros: Abseil 20220623 ships none, so the project keeps two small ones.
#ifndef SHEETMESH_COMMON_STATUS_MACROS_H_
#define SHEETMESH_COMMON_STATUS_MACROS_H_

#include <utility>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

#define SM_STATUS_CONCAT_INNER_(a, b) a##b
#define SM_STATUS_CONCAT_(a, b) SM_STATUS_CONCAT_INNER_(a, b)

// Evaluates `expr` (an absl::Status); returns it from the enclosing function if not OK.
#define SM_RETURN_IF_ERROR(expr)             \
  do {                                       \
    ::absl::Status sm_status_ = (expr);      \
    if (!sm_status_.ok()) return sm_status_; \
  } while (false)

// Evaluates `rexpr` (an absl::StatusOr<T>); on error returns its status, otherwise
// move-assigns the value to `lhs` (which may be a declaration: `auto x`).
#define SM_ASSIGN_OR_RETURN(lhs, rexpr) \
  SM_ASSIGN_OR_RETURN_IMPL_(SM_STATUS_CONCAT_(sm_statusor_, __LINE__), lhs, rexpr)

#define SM_ASSIGN_OR_RETURN_IMPL_(statusor, lhs, rexpr)    \
  auto statusor = (rexpr);                                 \
  if (!statusor.ok()) return std::move(statusor).status(); \
  lhs = std::move(statusor).value()

#endif  // SHEETMESH_COMMON_STATUS_MACROS_H_
