#include "common/orientation.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sheetmesh {

Orientation OrientationOf(const Vec3& normal) {
  Vec3 n = Normalized(normal);
  // With the normal pointing up, its horizontal part points down the dip.
  if (n.z < 0) n = -n;
  Orientation o;
  const double rad = 180.0 / std::numbers::pi;
  o.dip_degrees = std::acos(std::clamp(n.z, -1.0, 1.0)) * rad;
  const double h = std::hypot(n.x, n.y);
  if (h < 1e-12) return o;
  double az = std::atan2(n.x, n.y) * rad;
  if (az < 0) az += 360.0;
  if (az >= 360.0) az -= 360.0;
  o.dip_direction_degrees = az;
  return o;
}

double AngleBetweenNormalsDegrees(const Vec3& a, const Vec3& b) {
  const double c = std::abs(Dot(Normalized(a), Normalized(b)));
  return std::acos(std::clamp(c, 0.0, 1.0)) * 180.0 / std::numbers::pi;
}

}  // namespace sheetmesh
