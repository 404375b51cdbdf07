// Files made to hurt a reader from a few bytes: HDF5 files that name other files (external
// storage, virtual datasets, external links), chunk and nesting bombs, a NumPy header with a
// huge shape, JPEG and PNG slices claiming 65500 x 65500, a .vdb cut to its first bytes.
// Shared by the readers' tests and the service's hardening table.
#ifndef SHEETMESH_TESTS_TESTING_HOSTILE_FILES_H_
#define SHEETMESH_TESTS_TESTING_HOSTILE_FILES_H_

#include <cstdint>
#include <string>

namespace sheetmesh::testing {

// A 1x1x1 uint8 dataset /data whose one byte is stored in `external` at `offset`
// (h5py's create_dataset(..., external=[(external, offset, 1)])). Returns `path`.
std::string Hdf5WithExternalStorage(const std::string& path, const std::string& external,
                                    int64_t offset);
// A 4x4x4 uint8 virtual dataset /data mapped whole onto `source_file`:`source_dataset`.
std::string Hdf5Virtual(const std::string& path, const std::string& source_file,
                        const std::string& source_dataset);
// /data an external link to `target_file`:`target_object`.
std::string Hdf5ExternalLink(const std::string& path, const std::string& target_file,
                             const std::string& target_object);
// A plain 8x8x8 uint8 dataset `dataset` of sheet-like values (for links and sources).
std::string Hdf5Plain(const std::string& path, const std::string& dataset);
// A 48^3 uint8 dataset /data in one gzip chunk of chunk^3 voxels.
std::string Hdf5HugeChunk(const std::string& path, int chunk);
// `depth` nested groups /g/g/.../g with a 4^3 dataset at the bottom.
std::string Hdf5NestedGroups(const std::string& path, int depth);
// A dims-declaring dataset /data that was never written (no storage: fill values only).
std::string Hdf5NeverWritten(const std::string& path, int n);

// A .npy file whose shape tuple is `extents` ones: "(1,1,...,1,)".
std::string NpyWithLongShape(const std::string& path, int extents);
// A one-slice folder holding a small JPEG (or PNG) whose header claims width x height.
std::string JpegClaiming(const std::string& dir, int width, int height);
std::string PngClaiming(const std::string& dir, int width, int height);
// The first `bytes` bytes of a .vdb file of a small sheet volume.
std::string VdbCutTo(const std::string& path, int64_t bytes);

}  // namespace sheetmesh::testing

#endif  // SHEETMESH_TESTS_TESTING_HOSTILE_FILES_H_
