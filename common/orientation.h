// Geological orientation of a plane from its normal: dip and dip direction, z up, y north.
#ifndef SHEETMESH_COMMON_ORIENTATION_H_
#define SHEETMESH_COMMON_ORIENTATION_H_

#include "common/types.h"

namespace sheetmesh {

struct Orientation {
  double dip_degrees = 0;            // 0 = horizontal, 90 = vertical
  double dip_direction_degrees = 0;  // azimuth of steepest descent, clockwise from +y, [0, 360)
};

// Orientation of the plane with normal `n` (any sign, any length > 0). A horizontal plane
// has dip direction 0.
Orientation OrientationOf(const Vec3& n);

// Angle in degrees between the lines of two normals, in [0, 90] (sign-free).
double AngleBetweenNormalsDegrees(const Vec3& a, const Vec3& b);

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_ORIENTATION_H_
