// libFuzzer entry for sheetmesh::fuzz::FuzzDicomFile.
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  sheetmesh::fuzz::FuzzDicomFile(data, size);
  return 0;
}
