// Child readers: a volume read by a child process, so that a library that reads a damaged
// file past its buffers (OpenVDB, libhdf5, GDCM, libtiff, libpng, libjpeg) or allocates
// what the file declares kills or exhausts one child, not the command that asked. The
// child is a program's `_serve-volume` command (ServeVolume), started with an address-space
// limit; slices come back over a pipe.
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_CHILD_READER_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_CHILD_READER_H_

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "worker/pipeline/volume/volume_source.h"

namespace sheetmesh {

struct ChildReaderOptions {
  std::string program;          // runs `program _serve-volume SPEC`; "" = read in this process
  // The child must have opened the file within open_seconds plus a second for each
  // open_bytes_per_second of it (a folder: for each of its files), and answer each slab
  // within read_seconds plus a second for each 16 MiB of it. A library that loops on a
  // damaged file is stopped then.
  double open_seconds = 30;
  double open_bytes_per_second = 50e6;
  double read_seconds = 60;
  int64_t memory_slack = int64_t{1} << 30;  // address space beyond the reading budget
};

// Whether `format` (as InputFormatOf names it) is read by a third-party library that parses
// the file's structure: vdb, hdf5, dicom, png, jpeg, tiff and folders of slices. raw, nrrd,
// npy, mrc and nifti are parsed here and bounded by their own checks.
bool ReadByLibrary(const std::string& format);

// Opens `path` (of `format`, with the reader options `vdb_grid` and `limits`) in a child
// process. The child's address space is limited to the reading budget (MemoryBudget of
// `limits`) plus options.memory_slack. Errors the child's reader returns come back as they
// are; a child that dies, or takes longer than the options allow, is kInvalidArgument or
// kDeadlineExceeded naming the file, the format's library and how the child ended. The
// source's ReadSlices asks the child. Not thread-safe (as every VolumeSource).
absl::StatusOr<std::unique_ptr<VolumeSource>> OpenVolumeInChild(const std::string& path,
                                                                const std::string& format,
                                                                const std::string& vdb_grid,
                                                                const VolumeLimits& limits,
                                                                const ChildReaderOptions& options);

// What the child is asked to open.
struct ChildReaderSpec {
  std::string path;
  std::string format;
  std::string vdb_grid;
  VolumeLimits limits;  // memory_bytes: the parent's reading budget
};
// The spec OpenVolumeInChild passes on the child's command line. kInvalidArgument when it
// is not one.
absl::StatusOr<ChildReaderSpec> ParseChildReaderSpec(const std::string& text);

// The child's side: sends `opened` (the spec's volume opened in this process, or why not)
// on fd 3, then answers each slab asked on fd 4 until fd 4 ends. kAborted when the parent
// has gone.
absl::Status ServeVolume(absl::StatusOr<std::unique_ptr<VolumeSource>> opened);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_CHILD_READER_H_
