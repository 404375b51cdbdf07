// HDF5 datasets (beamline and ilastik-style files): "file.h5:/path/to/dataset", any
// chunking and any compression the HDF5 library decodes (deflate, szip, shuffle); and
// chunked, compressed HDF5 written slice by slice.
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_HDF5_IO_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_HDF5_IO_H_

#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "absl/status/statusor.h"
#include "worker/pipeline/volume/volume_sink.h"
#include "worker/pipeline/volume/volume_source.h"

namespace sheetmesh {

// Splits "scan.h5:/entry/data" into the file and the dataset when the part before the last
// ':' names a file ending .h5, .hdf5, .hdf, .he5 or .nxs; nullopt otherwise.
std::optional<std::pair<std::string, std::string>> SplitHdf5Path(const std::string& path);

// Whether `path` (without a dataset) ends like an HDF5 file.
bool HasHdf5Extension(const std::string& path);

// Opens `dataset` of the HDF5 file `file`: 3D (z, y, x; a 2D one is one slice), any integer
// or float type (uint8 and uint16 as they are, anything else read as float32). Spacing
// from the dataset's attributes "spacing" (x, y, z) with "unit" (a string), else
// "element_size_um" (z, y, x; unit "um"), else "spacing" alone. An empty `dataset` takes the file's
// only 2D/3D dataset. kNotFound naming the dataset and those the file has; kInvalidArgument for a
// file that is not HDF5, a dataset that is not 2D/3D or not numeric.
absl::StatusOr<std::unique_ptr<VolumeSource>> OpenHdf5Volume(const std::string& file,
                                                             const std::string& dataset,
                                                             const VolumeLimits& limits = {});

// Writes a volume of `info` as the dataset `dataset` ("volume" where empty) of a new HDF5 file
// at `path`: (z, y, x), chunks of 8 × 128 × 128 voxels shuffled and deflated, the spacing
// as attributes OpenHdf5Volume reads back ("spacing" and "unit", and "element_size_um" where
// the unit is a length). The file appears at `path` only when Finish() succeeds.
absl::StatusOr<std::unique_ptr<VolumeSink>> CreateHdf5Writer(const std::string& path,
                                                             const VolumeInfo& info,
                                                             const std::string& dataset = "");

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_HDF5_IO_H_
