// Entry points shared by the libFuzzer binaries and the corpus replay test: each takes
// arbitrary bytes and must return without crashing, hanging or allocating the impossible.
#ifndef SHEETMESH_TESTS_FUZZ_FUZZ_TARGETS_H_
#define SHEETMESH_TESTS_FUZZ_FUZZ_TARGETS_H_

#include <cstddef>
#include <cstdint>

namespace sheetmesh::fuzz {

// The NRRD header parser on `data` as header text.
void FuzzNrrdHeader(const uint8_t* data, size_t size);
// A whole volume file of one format, opened and read slice by slice under small limits (a
// 64 MiB memory budget): the bytes are a TIFF, an attached NRRD, an OpenVDB file; for raw,
// the first three bytes give the dims (and the first the type) and the rest is the file.
void FuzzTiffFile(const uint8_t* data, size_t size);
void FuzzNrrdFile(const uint8_t* data, size_t size);
void FuzzVdbFile(const uint8_t* data, size_t size);
void FuzzRawFile(const uint8_t* data, size_t size);
// An HDF5 file (its only dataset), a NumPy .npy file, and a one-slice folder of a JPEG or a
// PNG, each opened as a volume sent to the server is (naming no other file).
void FuzzHdf5File(const uint8_t* data, size_t size);
void FuzzNpyFile(const uint8_t* data, size_t size);
void FuzzDicomFile(const uint8_t* data, size_t size);
void FuzzNiftiFile(const uint8_t* data, size_t size);
void FuzzJpegFile(const uint8_t* data, size_t size);
void FuzzPngFile(const uint8_t* data, size_t size);
// Selection text, dims-in-file-name text and dtype names.
void FuzzTextParsers(const uint8_t* data, size_t size);

}  // namespace sheetmesh::fuzz

#endif  // SHEETMESH_TESTS_FUZZ_FUZZ_TARGETS_H_
