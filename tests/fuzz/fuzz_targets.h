// Entry points shared by the libFuzzer binaries and the corpus replay test: each takes
// arbitrary bytes and must return without crashing, hanging or allocating the impossible.
#ifndef SHEETMESH_TESTS_FUZZ_FUZZ_TARGETS_H_
#define SHEETMESH_TESTS_FUZZ_FUZZ_TARGETS_H_

#include <cstddef>
#include <cstdint>

namespace sheetmesh::fuzz {

// The NRRD header parser on `data` as header text.
void FuzzNrrdHeader(const uint8_t* data, size_t size);
// A whole volume file: the first byte picks raw / NRRD / TIFF, the rest is the file; raw
// dims and dtype come from the next bytes. Opens and reads every slice under small limits.
void FuzzVolumeFile(const uint8_t* data, size_t size);
// Selection text, dims-in-file-name text and dtype names.
void FuzzTextParsers(const uint8_t* data, size_t size);

}  // namespace sheetmesh::fuzz

#endif  // SHEETMESH_TESTS_FUZZ_FUZZ_TARGETS_H_
