// Small GoogleMock matchers for absl::Status and StatusOr: IsOk() and StatusIs(code[, msg]).
#ifndef SHEETMESH_TESTS_TESTING_STATUS_MATCHERS_H_
#define SHEETMESH_TESTS_TESTING_STATUS_MATCHERS_H_

#include <gmock/gmock.h>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace sheetmesh::testing {

inline const absl::Status& GetStatus(const absl::Status& s) { return s; }
template <class T>
const absl::Status& GetStatus(const absl::StatusOr<T>& s) {
  return s.status();
}

MATCHER(IsOk, "is OK") {
  const absl::Status& s = GetStatus(arg);
  if (!s.ok()) *result_listener << "status is " << s;
  return s.ok();
}

MATCHER_P(StatusIs, code, "has status code " + absl::StatusCodeToString(code)) {
  const absl::Status& s = GetStatus(arg);
  *result_listener << "status is " << s;
  return s.code() == code;
}

MATCHER_P2(StatusIs, code, message_matcher,
           "has status code " + absl::StatusCodeToString(code) + " and a matching message") {
  const absl::Status& s = GetStatus(arg);
  *result_listener << "status is " << s;
  return s.code() == code &&
         ::testing::Matches(message_matcher)(std::string(s.message()));
}

}  // namespace sheetmesh::testing

// Asserts that a StatusOr holds a value and moves it to `lhs`.
#define SM_ASSERT_OK_AND_ASSIGN(lhs, rexpr)                                   \
  SM_ASSERT_OK_AND_ASSIGN_IMPL_(SM_TEST_CONCAT_(sm_or_, __LINE__), lhs, rexpr)
#define SM_TEST_CONCAT_INNER_(a, b) a##b
#define SM_TEST_CONCAT_(a, b) SM_TEST_CONCAT_INNER_(a, b)
#define SM_ASSERT_OK_AND_ASSIGN_IMPL_(var, lhs, rexpr) \
  auto var = (rexpr);                                  \
  ASSERT_TRUE(var.ok()) << var.status();               \
  lhs = std::move(var).value()

#endif  // SHEETMESH_TESTS_TESTING_STATUS_MATCHERS_H_
