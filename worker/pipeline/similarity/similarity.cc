#include "worker/pipeline/similarity/similarity.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "worker/pipeline/core/status_macros.h"

namespace sheetmesh {

SimilarityScore ScoreModel(const VoxelSet& model, const VoxelSet& image) {
  assert(model.dims() == image.dims());
  SimilarityScore s;
  s.c_image = image.size();
  s.c_model = model.size();
  s.c_in = Intersection(model, image).size();
  s.c_out = s.c_model - s.c_in;
  s.similarity = s.c_image > 0 ? (double(s.c_in) - double(s.c_out)) / s.c_image : 0.0;
  s.dice = (s.c_model + s.c_image) > 0 ? 2.0 * s.c_in / double(s.c_model + s.c_image) : 0.0;
  return s;
}

namespace {

// Voxels of `set` with a face neighbour outside it: the only candidates for the nearest
// voxel to a point outside the set. Bucketed on a coarse grid for ring searches.
class NearestIndex {
 public:
  static constexpr int kBucket = 8;

  explicit NearestIndex(const VoxelSet& set) {
    set.ForEachVoxel([&](uint64_t, int32_t x, int32_t y, int32_t z) {
      const bool inner = set.Contains(x - 1, y, z) && set.Contains(x + 1, y, z) &&
                         set.Contains(x, y - 1, z) && set.Contains(x, y + 1, z) &&
                         set.Contains(x, y, z - 1) && set.Contains(x, y, z + 1);
      if (!inner) buckets_[Key(x / kBucket, y / kBucket, z / kBucket)].push_back({x, y, z});
    });
    const Dims& d = set.dims();
    max_ring_ = static_cast<int>(std::max({d.nx, d.ny, d.nz}) / kBucket + 2);
  }

  // Squared distance from p to the nearest indexed voxel (infinity if none).
  double Nearest2(const Index3& p) const {
    const int bx = p.x / kBucket, by = p.y / kBucket, bz = p.z / kBucket;
    double best = std::numeric_limits<double>::infinity();
    for (int ring = 0; ring <= max_ring_; ++ring) {
      // Every voxel in a bucket of ring >= 1 is at least (ring - 1) * kBucket away.
      const double floor_dist = std::max(0, ring - 1) * double(kBucket);
      if (floor_dist * floor_dist > best) break;
      for (int dz = -ring; dz <= ring; ++dz)
        for (int dy = -ring; dy <= ring; ++dy)
          for (int dx = -ring; dx <= ring; ++dx) {
            if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != ring) continue;
            auto it = buckets_.find(Key(bx + dx, by + dy, bz + dz));
            if (it == buckets_.end()) continue;
            for (const Index3& q : it->second) {
              const double ddx = q.x - p.x, ddy = q.y - p.y, ddz = q.z - p.z;
              best = std::min(best, ddx * ddx + ddy * ddy + ddz * ddz);
            }
          }
    }
    return best;
  }

 private:
  static uint64_t Key(int64_t x, int64_t y, int64_t z) {
    return (static_cast<uint64_t>(x & 0x1FFFFF) << 42) |
           (static_cast<uint64_t>(y & 0x1FFFFF) << 21) | static_cast<uint64_t>(z & 0x1FFFFF);
  }
  absl::flat_hash_map<uint64_t, std::vector<Index3>> buckets_;
  int max_ring_ = 0;
};

// Largest distance from a voxel of `from` (not in `to`) to `to`.
double Directed(const VoxelSet& from, const VoxelSet& to) {
  const VoxelSet outside = Difference(from, to);
  if (outside.empty()) return 0.0;
  const NearestIndex index(to);
  const std::vector<Index3> pts = outside.ToIndices();
  const double worst2 = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, pts.size(), 1024), 0.0,
      [&](const tbb::blocked_range<size_t>& r, double acc) {
        for (size_t i = r.begin(); i < r.end(); ++i) acc = std::max(acc, index.Nearest2(pts[i]));
        return acc;
      },
      [](double a, double b) { return std::max(a, b); });
  return std::sqrt(worst2);
}

}  // namespace

absl::StatusOr<double> HausdorffDistance(const VoxelSet& a, const VoxelSet& b,
                                         const Progress& progress) {
  if (a.empty() && b.empty()) return 0.0;
  if (a.empty() || b.empty()) return std::numeric_limits<double>::infinity();
  const double ab = Directed(a, b);
  SM_RETURN_IF_ERROR(progress.Update(0.5));
  const double ba = Directed(b, a);
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return std::max(ab, ba);
}

VoxelSet GridModel(const VoxelSet& image, int k) {
  assert(k >= 1);
  if (k == 1) return image;
  const Dims& d = image.dims();
  VoxelSet::Builder b(d);
  std::vector<Run> runs;
  for (int64_t z = 0; z < d.nz; ++z) {
    for (int64_t y = 0; y < d.ny; ++y) {
      // Row (y, z) repeats the kept voxels of the grid row it falls in.
      const int64_t sy = y - y % k, sz = z - z % k;
      runs.clear();
      for (const Run& r : image.RowRuns(sy, sz)) {
        // Multiples of k in [x0, x1), each blown up to [m, m + k).
        const int64_t first = (r.x0 + k - 1) / k * k;
        for (int64_t m = first; m < r.x1; m += k) {
          if (!runs.empty() && runs.back().x1 >= m) {
            runs.back().x1 = static_cast<int32_t>(m + k);
          } else {
            runs.push_back({static_cast<int32_t>(m), static_cast<int32_t>(m + k)});
          }
        }
      }
      for (const Run& r : runs) b.AddRun(y, z, r.x0, r.x1);
    }
  }
  return std::move(b).Build();
}

uint64_t GridQuantity(const Dims& dims, int k) {
  auto up = [k](int64_t n) { return static_cast<uint64_t>((n + k - 1) / k); };
  return up(dims.nx) * up(dims.ny) * up(dims.nz);
}

}  // namespace sheetmesh
