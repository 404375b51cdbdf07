// Where the real test volumes are; tests that need them skip with a message when absent.
#ifndef SHEETMESH_TESTS_TESTING_SHARED_DATA_H_
#define SHEETMESH_TESTS_TESTING_SHARED_DATA_H_

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace sheetmesh::testing {

// The folder of shared test volumes: $SHEETMESH_SHARED_DATA or the build's default.
inline std::string SharedDataDir() {
  if (const char* env = std::getenv("SHEETMESH_SHARED_DATA")) return env;
  return SHEETMESH_SHARED_DATA;
}

inline std::string SharedDataFile(const std::string& name) {
  return (std::filesystem::path(SharedDataDir()) / name).string();
}

}  // namespace sheetmesh::testing

// Skips the test when a shared data file is missing.
#define SM_REQUIRE_SHARED_DATA(name)                                                      \
  do {                                                                                    \
    if (!std::filesystem::exists(::sheetmesh::testing::SharedDataFile(name))) {           \
      GTEST_SKIP() << "shared test volume " << ::sheetmesh::testing::SharedDataFile(name) \
                   << " is absent; put ../shared/data beside the checkout or set "         \
                      "SHEETMESH_SHARED_DATA to run this test";                           \
    }                                                                                     \
  } while (false)

#endif  // SHEETMESH_TESTS_TESTING_SHARED_DATA_H_
