// Triangle meshes built in code for tests.
#ifndef SHEETMESH_TESTS_TESTING_MESHES_H_
#define SHEETMESH_TESTS_TESTING_MESHES_H_

#include <cstdint>

#include "worker/pipeline/mesh/triangle_mesh.h"

namespace sheetmesh::testing {

// A grid of n x m unit quads, two triangles each; vertex (x, y) is placed at `at(x, y)`
// and numbered y (n + 1) + x.
template <class At>
TriangleMesh Grid(int n, int m, At at) {
  TriangleMesh mesh;
  for (int y = 0; y <= m; ++y)
    for (int x = 0; x <= n; ++x) mesh.vertices.push_back(at(x, y));
  auto id = [n](int x, int y) { return static_cast<uint32_t>(y * (n + 1) + x); };
  for (int y = 0; y < m; ++y)
    for (int x = 0; x < n; ++x) {
      mesh.faces.push_back({id(x, y), id(x + 1, y), id(x + 1, y + 1)});
      mesh.faces.push_back({id(x, y), id(x + 1, y + 1), id(x, y + 1)});
    }
  return mesh;
}

}  // namespace sheetmesh::testing

#endif  // SHEETMESH_TESTS_TESTING_MESHES_H_
