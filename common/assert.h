// SM_ASSERT: a broken precondition is a bug; this stops the program naming it. On where
// NDEBUG is off or SHEETMESH_ASSERTS is defined (the tests' build: tools/test.sh), off
// otherwise, like SM_ASSERT(). Unlike SM_ASSERT(), it leaves the libraries' own asserts (OpenVDB,
// Eigen, TBB) alone, which make the tests several times slower when NDEBUG is off.
#ifndef SHEETMESH_COMMON_ASSERT_H_
#define SHEETMESH_COMMON_ASSERT_H_

namespace sheetmesh {

// Prints "FILE:LINE: assertion failed: CONDITION" and aborts.
[[noreturn]] void AssertFailed(const char* condition, const char* file, int line);

}  // namespace sheetmesh

#if defined(SHEETMESH_ASSERTS) || !defined(NDEBUG)
#define SM_ASSERTS_ON 1
#define SM_ASSERT(condition) \
  ((condition) ? static_cast<void>(0) : ::sheetmesh::AssertFailed(#condition, __FILE__, __LINE__))
#else
#define SM_ASSERTS_ON 0
#define SM_ASSERT(condition) static_cast<void>(0)
#endif

#endif  // SHEETMESH_COMMON_ASSERT_H_
