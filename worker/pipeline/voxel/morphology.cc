#include "worker/pipeline/voxel/morphology.h"

#include <algorithm>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/status_macros.h"

namespace sheetmesh {
namespace {

struct Offset {
  int dy, dz, widen;
};

std::vector<Offset> StructuringElement(Connectivity c) {
  std::vector<Offset> out;
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      const int off_axes = (dy != 0) + (dz != 0);
      int widen = -1;  // -1: row not part of the element
      switch (c) {
        case Connectivity::k6:
          widen = off_axes == 0 ? 1 : (off_axes == 1 ? 0 : -1);
          break;
        case Connectivity::k18:
          widen = off_axes <= 1 ? 1 : 0;
          break;
        case Connectivity::k26:
          widen = 1;
          break;
      }
      if (widen >= 0) out.push_back({dy, dz, widen});
    }
  }
  return out;
}

VoxelSet DilateStep(const VoxelSet& set, const std::vector<Offset>& element) {
  const Dims& d = set.dims();
  VoxelSet::Builder builder(d);
  std::vector<Run> gathered, merged;
  for (int64_t z = 0; z < d.nz; ++z) {
    for (int64_t y = 0; y < d.ny; ++y) {
      gathered.clear();
      for (const Offset& o : element) {
        const int64_t sy = y + o.dy, sz = z + o.dz;
        if (sy < 0 || sz < 0 || sy >= d.ny || sz >= d.nz) continue;
        for (const Run& r : set.RowRuns(sy, sz)) {
          gathered.push_back({r.x0 - o.widen, r.x1 + o.widen});
        }
      }
      if (gathered.empty()) continue;
      std::sort(gathered.begin(), gathered.end(),
                [](const Run& a, const Run& b) { return a.x0 < b.x0; });
      for (const Run& r : gathered) builder.AddRun(y, z, r.x0, r.x1);
    }
  }
  return std::move(builder).Build();
}

// Runs of `row` shrunk by `w` on each side; the box walls count as set.
void Shrink(std::span<const Run> row, int w, int32_t nx, std::vector<Run>* out) {
  out->clear();
  for (const Run& r : row) {
    const int32_t x0 = r.x0 == 0 ? 0 : r.x0 + w;
    const int32_t x1 = r.x1 == nx ? nx : r.x1 - w;
    if (x0 < x1) out->push_back({x0, x1});
  }
}

VoxelSet ErodeStep(const VoxelSet& set, const std::vector<Offset>& element) {
  const Dims& d = set.dims();
  const int32_t nx = static_cast<int32_t>(d.nx);
  VoxelSet::Builder builder(d);
  std::vector<Run> acc, shrunk, tmp;
  for (int64_t z = 0; z < d.nz; ++z) {
    for (int64_t y = 0; y < d.ny; ++y) {
      if (set.RowRuns(y, z).empty()) continue;
      Shrink(set.RowRuns(y, z), 1, nx, &acc);
      for (const Offset& o : element) {
        if (acc.empty()) break;
        if (o.dy == 0 && o.dz == 0) continue;
        const int64_t sy = y + o.dy, sz = z + o.dz;
        const bool outside = sy < 0 || sz < 0 || sy >= d.ny || sz >= d.nz;
        if (outside) continue;  // the wall counts as set
        Shrink(set.RowRuns(sy, sz), o.widen, nx, &shrunk);
        tmp.clear();
        IntersectRuns(acc, shrunk, &tmp);
        acc.swap(tmp);
      }
      for (const Run& r : acc) builder.AddRun(y, z, r.x0, r.x1);
    }
  }
  return std::move(builder).Build();
}

absl::Status CheckRadius(int radius) {
  if (radius < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("morphology radius ", radius, " must not be negative"));
  }
  return absl::OkStatus();
}

template <class Step>
absl::StatusOr<VoxelSet> Repeat(const VoxelSet& set, int radius, Connectivity c,
                                const Progress& progress, Step step) {
  SM_RETURN_IF_ERROR(CheckRadius(radius));
  const std::vector<Offset> element = StructuringElement(c);
  VoxelSet cur = set;
  for (int i = 0; i < radius; ++i) {
    cur = step(cur, element);
    SM_RETURN_IF_ERROR(progress.Update(double(i + 1) / radius));
  }
  return cur;
}

}  // namespace

absl::StatusOr<VoxelSet> Dilate(const VoxelSet& set, int radius_voxels, Connectivity c,
                                const Progress& progress) {
  return Repeat(set, radius_voxels, c, progress, DilateStep);
}

absl::StatusOr<VoxelSet> Erode(const VoxelSet& set, int radius_voxels, Connectivity c,
                               const Progress& progress) {
  return Repeat(set, radius_voxels, c, progress, ErodeStep);
}

absl::StatusOr<VoxelSet> Open(const VoxelSet& set, int radius_voxels, Connectivity c,
                              const Progress& progress) {
  SM_ASSIGN_OR_RETURN(VoxelSet e, Erode(set, radius_voxels, c, progress.Sub(0, 0.5)));
  return Dilate(e, radius_voxels, c, progress.Sub(0.5, 1));
}

absl::StatusOr<VoxelSet> Close(const VoxelSet& set, int radius_voxels, Connectivity c,
                               const Progress& progress) {
  SM_ASSIGN_OR_RETURN(VoxelSet dl, Dilate(set, radius_voxels, c, progress.Sub(0, 0.5)));
  return Erode(dl, radius_voxels, c, progress.Sub(0.5, 1));
}

}  // namespace sheetmesh
