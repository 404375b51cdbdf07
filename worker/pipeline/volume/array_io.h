// Volumes stored as one array after a header: NumPy .npy, MRC/CCP4 (.mrc .map .ccp4 .rec)
// and NIfTI-1 (.nii). Each header gives the dims, the voxel type and byte order, and
// (MRC, NIfTI) the spacing and origin. Types beyond uint8/uint16/float32 (int8, int16,
// uint32, int32, float64, or a NIfTI scaling) are read as float32; the format string says
// so ("nifti int16→float32").
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_ARRAY_IO_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_ARRAY_IO_H_

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "worker/pipeline/volume/volume_source.h"

namespace sheetmesh {

// NumPy .npy (versions 1–3): a 3D array (z, y, x) in C order, or (x, y, z) in Fortran
// order; a 2D array is one slice. No spacing is stored: 1. kInvalidArgument naming the
// file and the header field for a bad magic, a dtype that is not a number, a shape that
// is not 2D or 3D, or a file shorter than its array.
absl::StatusOr<std::unique_ptr<VolumeSource>> OpenNpyVolume(const std::string& path,
                                                            const VolumeLimits& limits = {});

// MRC 2014 / CCP4 maps: modes 0 (int8), 1 (int16), 2 (float32), 6 (uint16); spacing from
// the cell and the sampling (Å, unit "angstrom"), origin from the ORIGIN words (or the
// start indices). Columns, rows and sections must be x, y, z (MAPC/MAPR/MAPS 1, 2, 3).
absl::StatusOr<std::unique_ptr<VolumeSource>> OpenMrcVolume(const std::string& path,
                                                            const VolumeLimits& limits = {});

// NIfTI-1 single file (.nii, either byte order): spacing from pixdim, origin from the
// sform (or qform) translation, unit from xyzt_units; scl_slope/scl_inter applied. A
// gzipped .nii.gz, a NIfTI-2 file or a header pair (.hdr/.img) is kInvalidArgument saying
// what to do.
absl::StatusOr<std::unique_ptr<VolumeSource>> OpenNiftiVolume(const std::string& path,
                                                              const VolumeLimits& limits = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_ARRAY_IO_H_
