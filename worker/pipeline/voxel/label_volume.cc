#include "worker/pipeline/voxel/label_volume.h"

#include <algorithm>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "worker/pipeline/volume/hdf5_io.h"

namespace sheetmesh {

absl::Status WriteLabelVolume(const LabelledVoxels& model, const std::string& path,
                              VolumeFormat format, const Placement& placement) {
  for (int32_t l : model.label) {
    if (l < 0 || l > 65534) {
      return absl::InvalidArgumentError(
          absl::StrCat(path, ": label ", l, " does not fit a uint16 label volume"));
    }
  }
  const Dims& d = model.set.dims();
  VolumeInfo info;
  info.dims = d;
  info.dtype = DType::kUInt16;
  info.placement = placement;
  // HDF5: the dataset named for what it holds.
  SM_ASSIGN_OR_RETURN(auto sink, format == VolumeFormat::kHdf5
                                     ? CreateHdf5Writer(path, info, "labels")
                                     : CreateVolumeWriter(path, info, format));
  const int64_t slice = d.nx * d.ny;
  const int64_t slab = std::clamp<int64_t>((int64_t{16} << 20) / slice, 1, d.nz);
  std::vector<uint16_t> buf(static_cast<size_t>(slab * slice));
  for (int64_t z0 = 0; z0 < d.nz; z0 += slab) {
    const int64_t n = std::min(slab, d.nz - z0);
    std::fill(buf.begin(), buf.end(), 0);
    for (int64_t z = z0; z < z0 + n; ++z) {
      for (int64_t y = 0; y < d.ny; ++y) {
        const int64_t row = model.set.RowId(y, z);
        for (int64_t i = model.set.RowBegin(row); i < model.set.RowBegin(row + 1); ++i) {
          const Run& r = model.set.run(i);
          const uint64_t first = model.set.RunFirstIndex(i);
          for (int32_t x = r.x0; x < r.x1; ++x) {
            buf[((z - z0) * d.ny + y) * d.nx + x] =
                static_cast<uint16_t>(model.label[first + (x - r.x0)] + 1);
          }
        }
      }
    }
    SM_RETURN_IF_ERROR(sink->WriteSlices(
        n, std::span<const std::byte>(reinterpret_cast<const std::byte*>(buf.data()),
                                      static_cast<size_t>(n * slice * 2))));
  }
  return sink->Finish();
}

}  // namespace sheetmesh
