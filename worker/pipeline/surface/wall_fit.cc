#include "worker/pipeline/surface/wall_fit.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "worker/pipeline/surface/prism_columns.h"

namespace sheetmesh {
namespace {

// The number of voxels of the column (a prefix) the best height takes: a voxel no other
// prism holds gains 1 in the set and costs 1 outside it; one another prism holds, nothing.
size_t BestPrefix(const std::vector<ColumnVoxel>& column, const Coverage& cover) {
  int64_t score = 0, best = 0;
  size_t best_size = 0;
  for (size_t i = 0; i < column.size(); ++i) {
    if (cover.Count(column[i]) == 0) score += column[i].in_set ? 1 : -1;
    const bool tie_ahead = i + 1 < column.size() && column[i + 1].distance == column[i].distance;
    if (!tie_ahead && score > best) {
      best = score;
      best_size = i + 1;
    }
  }
  return best_size;
}

}  // namespace

std::vector<float> FitFaceThickness(const TriangleMesh& mesh, const VoxelSet& set,
                                    std::span<const float> max_height, int passes) {
  std::vector<float> out(mesh.faces.size(), 0.0f);
  std::vector<size_t> taken(mesh.faces.size(), 0);  // voxels of its column each face holds
  Coverage cover(set);
  // Columns are gathered in parallel a block of faces at a time; the descent over them is
  // sequential (each face's choice depends on the ones before).
  constexpr size_t kBlock =
      1024;  // each column holds its prism's voxels: at r = 15, 0.2 GB a block
  std::vector<std::vector<ColumnVoxel>> columns(kBlock);
  for (int pass = 0; pass < passes; ++pass) {
    for (size_t start = 0; start < mesh.faces.size(); start += kBlock) {
      const size_t end = std::min(mesh.faces.size(), start + kBlock);
      tbb::parallel_for(tbb::blocked_range<size_t>(start, end, 64),
                        [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t f = r.begin(); f < r.end(); ++f) {
                            ColumnOf(mesh, f, set, max_height[f] / 2, &columns[f - start]);
                          }
                        });
      for (size_t f = start; f < end; ++f) {
        const std::vector<ColumnVoxel>& column = columns[f - start];
        for (size_t i = 0; i < taken[f]; ++i) cover.Add(column[i], -1);
        taken[f] = BestPrefix(column, cover);
        for (size_t i = 0; i < taken[f]; ++i) cover.Add(column[i], +1);
        // The voxels taken stand for a voxel each: a voxel further than the last one's half
        // width, but short of the next voxel and within the column searched.
        if (taken[f] == 0) {
          out[f] = 0.0f;
          continue;
        }
        double h = std::min<double>(2 * column[taken[f] - 1].distance + 1, max_height[f]);
        if (taken[f] < column.size()) h = std::min(h, 2 * column[taken[f]].distance - 1e-3);
        out[f] = static_cast<float>(std::max(h, 2 * column[taken[f] - 1].distance + 1e-4));
      }
    }
  }
  return out;
}

}  // namespace sheetmesh
