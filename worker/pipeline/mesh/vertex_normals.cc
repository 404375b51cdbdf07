#include "worker/pipeline/mesh/vertex_normals.h"

#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {

std::vector<Vec3> VertexNormals(std::span<const Vec3> positions, std::span<const Face> faces) {
  std::vector<Vec3> sum(positions.size());
  std::vector<uint8_t> seen(positions.size(), 0);
  for (const Face& f : faces) {
    const Vec3 n = UnitNormal({positions[f[0]], positions[f[1]], positions[f[2]]});
    for (uint32_t v : f) {
      sum[v] += seen[v] && Dot(sum[v], n) < 0 ? -n : n;
      seen[v] = 1;
    }
  }
  for (Vec3& n : sum) n = Normalized(n);
  return sum;
}

}  // namespace sheetmesh
