// Shapes and measures shared by the tests of the volume mesh (PLC, TetGen, mesher).
#ifndef SHEETMESH_TESTS_WORKER_PIPELINE_TET_TET_TEST_SHAPES_H_
#define SHEETMESH_TESTS_WORKER_PIPELINE_TET_TET_TEST_SHAPES_H_

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/tet/plc.h"

namespace sheetmesh::testing {

// A sheet of n x n quads, each two triangles, over (u, v) in [a, b]² placed by `at` (voxel
// coordinates).
inline TriangleMesh Grid(const std::function<Vec3(double, double)>& at, double a, double b, int n,
                         int32_t piece = 0, float thick = 3) {
  TriangleMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.vertices.push_back(at(a + (b - a) * i / n, a + (b - a) * j / n));
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const uint32_t v = j * (n + 1) + i;
      m.faces.push_back({v, v + 1, v + n + 2});
      m.faces.push_back({v, v + n + 2, v + n + 1});
    }
  m.face_piece.assign(m.faces.size(), piece);
  m.face_thickness_voxels.assign(m.faces.size(), thick);
  return m;
}

// A square sheet of n x n quads at height z, spanning [a, b] in x and y (voxel coordinates).
inline TriangleMesh Square(double a, double b, double z, int n, int32_t piece = 0, float thick = 3,
                           int axis = 2) {
  return Grid(
      [&](double u, double v) {
        Vec3 p;
        p[axis] = z;
        p[(axis + 1) % 3] = u;
        p[(axis + 2) % 3] = v;
        return p;
      },
      a, b, n, piece, thick);
}

// The closed surface of the cube [lo, hi]^3 as a body (piece `piece`, thickness 0),
// outward, 12 triangles.
inline TriangleMesh Cube(double lo, double hi, int32_t piece) {
  TriangleMesh m;
  for (int c = 0; c < 8; ++c) {
    m.vertices.push_back({c & 1 ? hi : lo, c & 2 ? hi : lo, c & 4 ? hi : lo});
  }
  const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.faces.push_back({q[0], q[1], q[2]});
    m.faces.push_back({q[0], q[2], q[3]});
  }
  m.face_piece.assign(12, piece);
  m.face_thickness_voxels.assign(12, 0.f);
  m.body_pieces = {piece};
  return m;
}

inline TriangleMesh Append(TriangleMesh a, const TriangleMesh& b) {
  const uint32_t off = static_cast<uint32_t>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (Face f : b.faces) a.faces.push_back({f[0] + off, f[1] + off, f[2] + off});
  a.face_piece.insert(a.face_piece.end(), b.face_piece.begin(), b.face_piece.end());
  a.face_thickness_voxels.insert(a.face_thickness_voxels.end(), b.face_thickness_voxels.begin(),
                                 b.face_thickness_voxels.end());
  return a;
}

// The distance from p to the PLC's nearest sheet triangle.
inline double DistanceToSheets(const Plc& plc, const Vec3& p) {
  double d2 = 1e300;
  for (const Face& t : plc.sheet_triangles) {
    d2 = std::min(d2, PointTriangleDistance2(
                          p, {plc.vertices[t[0]], plc.vertices[t[1]], plc.vertices[t[2]]}));
  }
  return std::sqrt(d2);
}

// The smallest distance between two of `pts`.
inline double ClosestPair(const std::vector<Vec3>& pts) {
  double best = 1e300;
  for (size_t i = 0; i < pts.size(); ++i)
    for (size_t j = i + 1; j < pts.size(); ++j) best = std::min(best, Norm(pts[i] - pts[j]));
  return best;
}

}  // namespace sheetmesh::testing

#endif  // SHEETMESH_TESTS_WORKER_PIPELINE_TET_TET_TEST_SHAPES_H_
