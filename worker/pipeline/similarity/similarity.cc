#include "worker/pipeline/similarity/similarity.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <nanoflann.hpp>
#include <vector>

#include "common/assert.h"
#include "common/status_macros.h"

namespace sheetmesh {

SimilarityScore ScoreModel(const VoxelSet& model, const VoxelSet& image) {
  SM_ASSERT(model.dims() == image.dims());
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
// voxel to a point outside the set; kept in a k-d tree.
class NearestIndex {
 public:
  explicit NearestIndex(const VoxelSet& set)
      : tree_(3, cloud_,
              nanoflann::KDTreeSingleIndexAdaptorParams(
                  16, nanoflann::KDTreeSingleIndexAdaptorFlags::SkipInitialBuildIndex)) {
    set.ForEachVoxel([&](uint64_t, int32_t x, int32_t y, int32_t z) {
      const bool inner = set.Contains(x - 1, y, z) && set.Contains(x + 1, y, z) &&
                         set.Contains(x, y - 1, z) && set.Contains(x, y + 1, z) &&
                         set.Contains(x, y, z - 1) && set.Contains(x, y, z + 1);
      if (!inner) cloud_.pts.push_back({x, y, z});
    });
    tree_.buildIndex();
  }

  // Squared distance from p to the nearest indexed voxel (infinity if none).
  double Nearest2(const Index3& p) const {
    if (cloud_.pts.empty()) return std::numeric_limits<double>::infinity();
    const double q[3] = {double(p.x), double(p.y), double(p.z)};
    uint32_t index = 0;
    double d2 = 0;
    nanoflann::KNNResultSet<double, uint32_t, uint32_t> result(1);
    result.init(&index, &d2);
    tree_.findNeighbors(result, q, nanoflann::SearchParams());
    return d2;
  }

 private:
  struct Cloud {
    std::vector<Index3> pts;
    size_t kdtree_get_point_count() const { return pts.size(); }
    double kdtree_get_pt(size_t i, size_t dim) const {
      return dim == 0 ? pts[i].x : (dim == 1 ? pts[i].y : pts[i].z);
    }
    template <class Box>
    bool kdtree_get_bbox(Box&) const {
      return false;
    }
  };
  using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Cloud>,
                                                   Cloud, 3, uint32_t>;
  Cloud cloud_;
  Tree tree_;
};

// Largest distance from a voxel of `from` (not in `to`) to `to`.
double Directed(const VoxelSet& from, const VoxelSet& to) {
  const VoxelSet outside = Difference(from, to);
  if (outside.empty()) return 0.0;
  const NearestIndex index(to);
  const std::vector<Index3> pts = outside.ToIndices();
  return std::sqrt(tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, pts.size(), 4096), 0.0,
      [&](const tbb::blocked_range<size_t>& r, double acc) {
        for (size_t i = r.begin(); i < r.end(); ++i) acc = std::max(acc, index.Nearest2(pts[i]));
        return acc;
      },
      [](double a, double b) { return std::max(a, b); }));
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
  SM_ASSERT(k >= 1);
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
