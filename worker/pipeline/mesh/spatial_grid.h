// SpatialGrid: a uniform hash grid of boxes, for finding triangles near a triangle.
#ifndef SHEETMESH_WORKER_PIPELINE_MESH_SPATIAL_GRID_H_
#define SHEETMESH_WORKER_PIPELINE_MESH_SPATIAL_GRID_H_

#include <cmath>
#include <cstdint>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "common/types.h"

namespace sheetmesh {

// Not thread-safe for insertion; queries may run concurrently once built.
class SpatialGrid {
 public:
  explicit SpatialGrid(double cell_size) : inv_(1.0 / cell_size) {}

  // Adds `id` to every cell its box [lo, hi] overlaps.
  void Insert(uint32_t id, const Vec3& lo, const Vec3& hi) {
    ForCells(lo, hi, [&](uint64_t key) { cells_[key].push_back(id); });
  }
  // Calls f(id) for each id in a cell the box overlaps; an id may come more than once.
  template <class F>
  void Query(const Vec3& lo, const Vec3& hi, F&& f) const {
    ForCells(lo, hi, [&](uint64_t key) {
      auto it = cells_.find(key);
      if (it == cells_.end()) return;
      for (uint32_t id : it->second) f(id);
    });
  }

 private:
  template <class F>
  void ForCells(const Vec3& lo, const Vec3& hi, F&& f) const {
    const int64_t x0 = Cell(lo.x), x1 = Cell(hi.x), y0 = Cell(lo.y), y1 = Cell(hi.y);
    const int64_t z0 = Cell(lo.z), z1 = Cell(hi.z);
    for (int64_t z = z0; z <= z1; ++z)
      for (int64_t y = y0; y <= y1; ++y)
        for (int64_t x = x0; x <= x1; ++x) f(Key(x, y, z));
  }
  int64_t Cell(double v) const { return static_cast<int64_t>(std::floor(v * inv_)); }
  static uint64_t Key(int64_t x, int64_t y, int64_t z) {
    return (static_cast<uint64_t>(x & 0x1FFFFF) << 42) |
           (static_cast<uint64_t>(y & 0x1FFFFF) << 21) | static_cast<uint64_t>(z & 0x1FFFFF);
  }

  double inv_;
  absl::flat_hash_map<uint64_t, std::vector<uint32_t>> cells_;
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_MESH_SPATIAL_GRID_H_
