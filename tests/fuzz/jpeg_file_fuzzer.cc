// libFuzzer entry for sheetmesh::fuzz::FuzzJpegFile.
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  sheetmesh::fuzz::FuzzJpegFile(data, size);
  return 0;
}
