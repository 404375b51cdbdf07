#include "worker/pipeline/voxel/neighbor_table.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "absl/strings/str_cat.h"

namespace sheetmesh {
namespace {

// Links the voxels of row `a` to those of row `b` that share their x: a's voxels get `b`
// as neighbour in direction `ka`, b's get `a` in direction `kb`.
void LinkRows(const VoxelSet& set, int64_t row_a, int64_t row_b, int ka, int kb,
              std::vector<std::array<uint32_t, 4>>* t) {
  int64_t i = set.RowBegin(row_a), ie = set.RowBegin(row_a + 1);
  int64_t j = set.RowBegin(row_b), je = set.RowBegin(row_b + 1);
  while (i < ie && j < je) {
    const Run& ra = set.run(i);
    const Run& rb = set.run(j);
    const int32_t lo = std::max(ra.x0, rb.x0), hi = std::min(ra.x1, rb.x1);
    if (lo < hi) {
      const uint64_t fa = set.RunFirstIndex(i) + (lo - ra.x0);
      const uint64_t fb = set.RunFirstIndex(j) + (lo - rb.x0);
      for (int32_t k = 0; k < hi - lo; ++k) {
        (*t)[fa + k][ka - 2] = static_cast<uint32_t>(fb + k);
        (*t)[fb + k][kb - 2] = static_cast<uint32_t>(fa + k);
      }
    }
    if (ra.x1 < rb.x1) {
      ++i;
    } else {
      ++j;
    }
  }
}

}  // namespace

absl::StatusOr<NeighborTable> NeighborTable::Build(const VoxelSet& set) {
  if (set.size() >= kNoNeighbor) {
    return absl::ResourceExhaustedError(
        absl::StrCat(set.size(), " sheet voxels exceed the neighbour table's 2^32 limit"));
  }
  NeighborTable nt;
  std::array<uint32_t, 4> none;
  none.fill(kNoNeighbor);
  nt.across_.assign(set.size(), none);
  nt.along_.assign(set.size(), 0);
  auto& t = nt.across_;
  auto& along = nt.along_;
  const Dims& d = set.dims();
  // The task of slice z writes the x and y entries of slice z, its +z entries and the -z
  // entries of slice z + 1: no entry is written by two tasks.
  tbb::parallel_for(tbb::blocked_range<int64_t>(0, d.nz),
                    [&](const tbb::blocked_range<int64_t>& r) {
                      for (int64_t z = r.begin(); z < r.end(); ++z) {
                        for (int64_t y = 0; y < d.ny; ++y) {
                          const int64_t row = set.RowId(y, z);
                          for (int64_t i = set.RowBegin(row); i < set.RowBegin(row + 1); ++i) {
                            const Run& run = set.run(i);
                            const uint64_t first = set.RunFirstIndex(i);
                            for (int32_t k = 1; k < run.length(); ++k) {
                              along[first + k] |= 1;      // first + k - 1 before it
                              along[first + k - 1] |= 2;  // first + k after it
                            }
                          }
                          if (y + 1 < d.ny) LinkRows(set, row, set.RowId(y + 1, z), 3, 2, &t);
                          if (z + 1 < d.nz) LinkRows(set, row, set.RowId(y, z + 1), 5, 4, &t);
                        }
                      }
                    });
  return nt;
}

}  // namespace sheetmesh
