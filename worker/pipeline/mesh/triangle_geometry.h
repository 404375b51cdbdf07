// Geometry of single triangles: normals, areas, dihedral angles, distances, projections
// and a triangle-triangle intersection test.
#ifndef SHEETMESH_WORKER_PIPELINE_MESH_TRIANGLE_GEOMETRY_H_
#define SHEETMESH_WORKER_PIPELINE_MESH_TRIANGLE_GEOMETRY_H_

#include <algorithm>
#include <array>
#include <utility>
#include <vector>

#include "common/types.h"
#include "worker/pipeline/mesh/triangle_mesh.h"

namespace sheetmesh {

using Triangle = std::array<Vec3, 3>;

// (b - a) x (c - a): twice the area, along the normal of counter-clockwise a, b, c.
inline Vec3 AreaVector(const Triangle& t) { return Cross(t[1] - t[0], t[2] - t[0]); }
inline double Area(const Triangle& t) { return 0.5 * Norm(AreaVector(t)); }
inline Vec3 UnitNormal(const Triangle& t) { return Normalized(AreaVector(t)); }
// The triangle's axis-aligned bounding box, grown by `grow` on every side.
inline void TriangleBox(const Triangle& t, double grow, Vec3* lo, Vec3* hi) {
  for (int k = 0; k < 3; ++k) {
    (*lo)[k] = std::min({t[0][k], t[1][k], t[2][k]}) - grow;
    (*hi)[k] = std::max({t[0][k], t[1][k], t[2][k]}) + grow;
  }
}

// The smallest and the largest interior angle, degrees (a corner with a zero-length edge
// counts as 0).
std::pair<double, double> AngleRangeDegrees(const Triangle& t);
// The smallest interior angle, degrees (0 for a degenerate triangle).
inline double MinAngleDegrees(const Triangle& t) { return AngleRangeDegrees(t).first; }
// The angle between two vectors, degrees (180 when either is zero).
double AngleDegrees(const Vec3& a, const Vec3& b);

// Dihedral angle at edge (p, q) between the half-planes towards r and towards s, measured
// perpendicular to the edge, in degrees: 180 = flat continuation, 0 = folded back
// (ALGORITHM §5). Orientation-free. 180 when either triangle is degenerate.
double DihedralAngleDegrees(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s);

// The point of the segment [a, b] nearest `p` (a when the segment has no length).
Vec3 ClosestOnSegment(const Vec3& p, const Vec3& a, const Vec3& b);

// The point of the closed triangle nearest `p`, and the squared distance to it.
Vec3 ClosestPointOnTriangle(const Vec3& p, const Triangle& t);
double PointTriangleDistance2(const Vec3& p, const Triangle& t);

// Whether `p` lies inside the closed surface made of `faces` of `vertices`, by the parity
// of the crossings of a ray along +x.
bool InsideClosedSurface(const Vec3& p, const std::vector<Vec3>& vertices,
                         const std::vector<Face>& faces);

// Barycentric coordinates (u, v, w) of the projection of `p` onto the triangle's plane:
// projection = u a + v b + w c. False for a degenerate triangle.
bool ProjectBarycentric(const Vec3& p, const Triangle& t, double* u, double* v, double* w);

// True when the two closed triangles intersect, by separating axes (both normals, the nine
// edge cross products and the in-plane edge normals, so coplanar triangles work too).
// Triangles that touch, or come within `tolerance`, count as intersecting (test shrunken
// copies of triangles that share a vertex).
bool TrianglesIntersect(const Triangle& a, const Triangle& b, double tolerance = 1e-9);

// `t` shrunk towards its centroid by `fraction` of the way: used to test triangles that
// share a vertex or an edge for overlap beyond it.
Triangle Shrink(const Triangle& t, double fraction);

// Mean edge length over all edges of all faces (the paper's "element size"), 0 if empty.
double MeanEdgeLength(const TriangleMesh& mesh);
// Total area.
double SurfaceArea(const TriangleMesh& mesh);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_MESH_TRIANGLE_GEOMETRY_H_
