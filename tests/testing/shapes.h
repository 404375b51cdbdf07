// Sheet shapes built in code for tests: slabs, tilted slabs, cylindrical shells, discs with
// holes, crossing slabs.
#ifndef SHEETMESH_TESTS_TESTING_SHAPES_H_
#define SHEETMESH_TESTS_TESTING_SHAPES_H_

#include <cmath>
#include <functional>
#include <vector>

#include "common/types.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh::testing {

// The voxels of `dims` for which `inside(x, y, z)` holds.
inline VoxelSet ShapeSet(const Dims& dims,
                         const std::function<bool(double, double, double)>& inside) {
  VoxelSet::Builder b(dims);
  for (int64_t z = 0; z < dims.nz; ++z)
    for (int64_t y = 0; y < dims.ny; ++y)
      for (int64_t x = 0; x < dims.nx; ++x)
        if (inside(x, y, z)) b.AddVoxel(x, y, z);
  return std::move(b).Build();
}

// A box [lo, hi) of voxels.
inline VoxelSet BoxSet(const Dims& dims, Index3 lo, Index3 hi) {
  return ShapeSet(dims, [=](double x, double y, double z) {
    return x >= lo.x && x < hi.x && y >= lo.y && y < hi.y && z >= lo.z && z < hi.z;
  });
}

// Voxels within thickness/2 of the plane through `p` with unit normal `n`, inside `margin`
// of the box walls.
inline VoxelSet PlaneSlab(const Dims& dims, Vec3 p, Vec3 n, double thickness, int margin = 2) {
  n = Normalized(n);
  return ShapeSet(dims, [=](double x, double y, double z) {
    if (x < margin || y < margin || z < margin || x >= dims.nx - margin || y >= dims.ny - margin ||
        z >= dims.nz - margin) {
      return false;
    }
    return std::abs(Dot(Vec3(x, y, z) - p, n)) <= thickness / 2;
  });
}

// A cylindrical shell around the z axis through (cx, cy): radius r (mid-surface), thickness t,
// z in [z0, z1), spanning `arc` radians from angle 0.
inline VoxelSet CylinderShell(const Dims& dims, double cx, double cy, double r, double t, int z0,
                              int z1, double arc = 2 * M_PI) {
  return ShapeSet(dims, [=](double x, double y, double z) {
    if (z < z0 || z >= z1) return false;
    double a = std::atan2(y - cy, x - cx);
    if (a < 0) a += 2 * M_PI;
    if (a > arc) return false;
    return std::abs(std::hypot(x - cx, y - cy) - r) <= t / 2;
  });
}

}  // namespace sheetmesh::testing

#endif  // SHEETMESH_TESTS_TESTING_SHAPES_H_
