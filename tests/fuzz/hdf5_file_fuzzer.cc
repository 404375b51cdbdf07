// libFuzzer entry for sheetmesh::fuzz::FuzzHdf5File.
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  sheetmesh::fuzz::FuzzHdf5File(data, size);
  return 0;
}
