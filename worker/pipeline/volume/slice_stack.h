// Volumes stored as one 2D image per z slice: a folder of TIFF, PNG, JPEG or DICOM files.
// Each image format is a SliceCodec (what a slice's header says, how its pixels decode);
// one stack source orders the files, checks that they agree, and reads them slice by slice.
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_SLICE_STACK_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_SLICE_STACK_H_

#include <array>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "worker/pipeline/volume/volume_source.h"

namespace sheetmesh {

// What one slice file says before its pixels are decoded.
struct SliceHeader {
  uint32_t width = 0;
  uint32_t height = 0;
  DType dtype = DType::kUInt8;  // the type its pixels read as
  // "8-bit grey", "16-bit signed, rescaled": for messages when slices disagree.
  std::string kind;
  // Spacing and unit, when the file stores them (ImageJ TIFF, DICOM).
  std::optional<Placement> placement;
  // DICOM: where the slice lies (ImagePositionPatient, mm), its row and column direction
  // cosines, its series and instance number; the stack orders and spaces slices by them.
  std::optional<Vec3> position;
  std::optional<std::array<double, 6>> orientation;
  std::string series;
  std::optional<int64_t> instance;
};

class SliceCodec {
 public:
  virtual ~SliceCodec() = default;
  // "tiff", "png", "jpeg", "dicom".
  virtual std::string name() const = 0;
  // Whether `file` (a regular file in the folder) is a slice of this format, by name or
  // magic bytes.
  virtual bool Claims(const std::string& file) const = 0;
  // The header; kInvalidArgument naming the file and field for what cannot be read, and
  // kResourceExhausted when one slice would not fit the memory budget.
  virtual absl::StatusOr<SliceHeader> ReadHeader(const std::string& file,
                                                 const VolumeLimits& limits) const = 0;
  // Decodes `file` into `out` (width * height voxels of `dtype`, x fastest). `expected` is
  // the first slice's header: a file that no longer agrees with it is kInvalidArgument
  // naming both. A codec may widen its pixels to `dtype` (DICOM to float32 for rescaled
  // values).
  virtual absl::Status ReadSlice(const std::string& file, const SliceHeader& expected, DType dtype,
                                 std::span<std::byte> out) const = 0;
};

std::unique_ptr<SliceCodec> MakeTiffSliceCodec();   // tiff_io.cc
std::unique_ptr<SliceCodec> MakePngSliceCodec();    // image_slices.cc
std::unique_ptr<SliceCodec> MakeJpegSliceCodec();   // image_slices.cc
std::unique_ptr<SliceCodec> MakeDicomSliceCodec();  // dicom_io.cc

// Opens a folder of slices. The format is that of the folder's slice files (hidden files
// and a DICOMDIR are ignored); a folder mixing formats is kInvalidArgument naming them,
// one with no slices kNotFound. TIFF, PNG and JPEG slices are ordered by the numbers in
// their names ("s2.png" before "s10.png"); DICOM slices by their position along the
// slice normal (or instance number), with the z spacing from the positions, which must be
// even. Every slice's header is read at open: slices that differ in size or type fail
// there, naming both files.
absl::StatusOr<std::unique_ptr<VolumeSource>> OpenSliceFolder(const std::string& folder,
                                                              const VolumeLimits& limits = {});

// The same for a folder that must hold slices of `codec_name` ("tiff", ...).
absl::StatusOr<std::unique_ptr<VolumeSource>> OpenSliceFolderOf(const std::string& folder,
                                                                const std::string& codec_name,
                                                                const VolumeLimits& limits = {});

// One PNG or JPEG image as a volume one slice deep.
absl::StatusOr<std::unique_ptr<VolumeSource>> OpenSingleSlice(const std::string& file,
                                                              const std::string& codec_name,
                                                              const VolumeLimits& limits = {});

// Orders names by their digit runs read as numbers, so "s2" < "s10".
bool NaturalLess(const std::string& a, const std::string& b);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_SLICE_STACK_H_
