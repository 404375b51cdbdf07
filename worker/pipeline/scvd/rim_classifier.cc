#include "worker/pipeline/scvd/rim_classifier.h"

#include <cmath>

namespace sheetmesh {

RimClassifier::RimClassifier(const VoxelSet& set, double max_cos) : set_(set), max_cos_(max_cos) {
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        if (dx != 0 || dy != 0 || dz != 0) dirs_.emplace_back(dx, dy, dz);
}

bool RimClassifier::IsRim(int32_t x, int32_t y, int32_t z, const Vec3& n) const {
  // A step across the sheet also leaves it on the faces of a stepped, tilted sheet, so
  // only steps along it count.
  for (const Vec3& d : dirs_) {
    if (std::abs(Dot(d, n)) >= max_cos_ * Norm(d)) continue;
    if (!set_.Contains(x + static_cast<int32_t>(d.x), y + static_cast<int32_t>(d.y),
                       z + static_cast<int32_t>(d.z))) {
      return true;
    }
  }
  return false;
}

}  // namespace sheetmesh
