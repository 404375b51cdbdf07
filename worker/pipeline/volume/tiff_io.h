// TIFF volumes: one multi-page file (a page per z slice) or a folder of single-page slices,
// 8-bit, 16-bit unsigned or 32-bit float, any compression libtiff decodes, strips or tiles.
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_TIFF_IO_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_TIFF_IO_H_

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "worker/pipeline/volume/volume_sink.h"
#include "worker/pipeline/volume/volume_source.h"

namespace sheetmesh {

// Opens a multi-page TIFF. Every page must have the same width, height and sample type:
// kInvalidArgument naming the page and both sizes otherwise, and for unsupported samples
// (bits, sample format, more than one sample per pixel). Spacing and unit come from an
// ImageJ description when present.
absl::StatusOr<std::unique_ptr<VolumeSource>> OpenTiffVolume(const std::string& path,
                                                             const VolumeLimits& limits = {});

// Opens a folder of single-page TIFF slices (*.tif, *.tiff) through OpenSliceFolderOf
// (slice_stack.h), ordered by the numbers in their names ("s2.tif" before "s10.tif"). kNotFound
// when the folder holds no TIFF; kInvalidArgument when slices differ in size or type (naming both
// files).
absl::StatusOr<std::unique_ptr<VolumeSource>> OpenTiffFolder(const std::string& folder,
                                                             const VolumeLimits& limits = {});

// Writes a multi-page TIFF (BigTIFF when above 2 GiB), uncompressed unless `deflate`.
absl::StatusOr<std::unique_ptr<VolumeSink>> CreateTiffWriter(const std::string& path,
                                                             const VolumeInfo& info,
                                                             bool deflate = false);

// Writes a folder of single-page slices named slice_00000.tif, ... The folder is created
// if missing; each slice appears atomically.
absl::StatusOr<std::unique_ptr<VolumeSink>> CreateTiffFolderWriter(const std::string& folder,
                                                                   const VolumeInfo& info);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_TIFF_IO_H_
