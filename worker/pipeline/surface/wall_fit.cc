#include "worker/pipeline/surface/wall_fit.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "absl/container/flat_hash_map.h"
#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {
namespace {

// A voxel of a face's column: its distance to the face's plane, and the voxel (its index in
// the set, or its linear index, marked by `in_set`).
struct ColumnVoxel {
  double distance;
  uint64_t id;
  bool in_set;
  bool operator<(const ColumnVoxel& o) const { return distance < o.distance; }
};

// The voxels whose centres project into face f's triangle within `pad` of its plane, by
// distance.
void ColumnOf(const TriangleMesh& mesh, size_t f, const VoxelSet& set, double pad,
              std::vector<ColumnVoxel>* column) {
  column->clear();
  const Dims& d = set.dims();
  const Triangle t = Corners(mesh, f);
  const Vec3 n = UnitNormal(t);
  if (Norm2(n) == 0 || !(pad > 0)) return;
  // Barycentric coordinates of the projection of p along n are affine in p:
  // v = A·(p - t0), w = B·(p - t0), u = 1 - v - w (as ProjectBarycentric computes them).
  const Vec3 e1 = t[1] - t[0], e2 = t[2] - t[0];
  const double g11 = Dot(e1, e1), g12 = Dot(e1, e2), g22 = Dot(e2, e2);
  const double det = g11 * g22 - g12 * g12;
  if (!(std::abs(det) > 1e-18 * (g11 * g22 + 1e-300))) return;
  const Vec3 A = (e1 * g22 - e2 * g12) * (1.0 / det), B = (e2 * g11 - e1 * g12) * (1.0 / det);
  // Walk the prism along the axis k nearest its normal: for each cell (i, j) of the other
  // two axes within the prism's box, the k-range where all four affine conditions hold.
  const int k = std::abs(n.x) >= std::abs(n.y) && std::abs(n.x) >= std::abs(n.z)
                    ? 0
                    : (std::abs(n.y) >= std::abs(n.z) ? 1 : 2);
  const int ia = (k + 1) % 3, ja = (k + 2) % 3;
  const int64_t extent[3] = {d.nx, d.ny, d.nz};
  auto range = [&](int axis, int64_t* lo, int64_t* hi) {
    const double reach = pad * std::abs(n[axis]);
    *lo = std::max<int64_t>(0, static_cast<int64_t>(std::ceil(
                                   std::min({t[0][axis], t[1][axis], t[2][axis]}) - reach - 1e-9)));
    *hi = std::min<int64_t>(extent[axis] - 1,
                            static_cast<int64_t>(std::floor(
                                std::max({t[0][axis], t[1][axis], t[2][axis]}) + reach + 1e-9)));
  };
  int64_t ilo, ihi, jlo, jhi;
  range(ia, &ilo, &ihi);
  range(ja, &jlo, &jhi);
  constexpr double kEps = 1e-9;
  for (int64_t i = ilo; i <= ihi; ++i) {
    for (int64_t j = jlo; j <= jhi; ++j) {
      // Each condition f0 + c f1 >= 0 (f1 the coefficient of the k coordinate c) bounds c.
      Vec3 q0;
      q0[ia] = double(i) - t[0][ia];
      q0[ja] = double(j) - t[0][ja];
      q0[k] = -t[0][k];
      double clo = 0, chi = double(extent[k] - 1);
      auto bound = [&](double f0, double f1) {
        if (std::abs(f1) < 1e-15) {
          if (f0 < 0) chi = -1;  // never
        } else if (f1 > 0) {
          clo = std::max(clo, -f0 / f1);
        } else {
          chi = std::min(chi, -f0 / f1);
        }
      };
      const double v0 = Dot(A, q0), w0 = Dot(B, q0), dist0 = Dot(n, q0);
      bound(v0 + kEps, A[k]);
      bound(w0 + kEps, B[k]);
      bound(1 - v0 - w0 + kEps, -A[k] - B[k]);
      bound(pad - dist0, -n[k]);
      bound(pad + dist0, n[k]);
      if (clo > chi) continue;
      for (int64_t c = static_cast<int64_t>(std::ceil(clo - kEps));
           c <= static_cast<int64_t>(std::floor(chi + kEps)); ++c) {
        const Vec3 q(q0[0] + (k == 0 ? double(c) : 0.0), q0[1] + (k == 1 ? double(c) : 0.0),
                     q0[2] + (k == 2 ? double(c) : 0.0));
        const double v = Dot(A, q), w = Dot(B, q), dist = std::abs(Dot(n, q));
        if (v < -kEps || w < -kEps || 1 - v - w < -kEps || dist > pad) continue;
        int64_t xyz[3];
        xyz[k] = c;
        xyz[ia] = i;
        xyz[ja] = j;
        const int64_t at = set.Find(xyz[0], xyz[1], xyz[2]);
        column->push_back(
            {dist, at >= 0 ? uint64_t(at) : uint64_t((xyz[2] * d.ny + xyz[1]) * d.nx + xyz[0]),
             at >= 0});
      }
    }
  }
  std::sort(column->begin(), column->end());
}

// How many prisms hold each voxel: the set's by index, the others by linear index.
class Coverage {
 public:
  explicit Coverage(const VoxelSet& set) : in_(set.size(), 0) {}
  uint32_t Count(const ColumnVoxel& c) const {
    if (c.in_set) return in_[c.id];
    auto it = out_.find(c.id);
    return it == out_.end() ? 0 : it->second;
  }
  void Add(const ColumnVoxel& c, int delta) {
    if (c.in_set) {
      in_[c.id] = static_cast<uint32_t>(int64_t(in_[c.id]) + delta);
    } else {
      uint32_t& n = out_[c.id];
      n = static_cast<uint32_t>(int64_t(n) + delta);
    }
  }

 private:
  std::vector<uint32_t> in_;
  absl::flat_hash_map<uint64_t, uint32_t> out_;
};

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
  constexpr size_t kBlock = 4096;
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
