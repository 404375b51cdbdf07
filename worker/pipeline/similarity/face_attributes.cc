#include "worker/pipeline/similarity/face_attributes.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {

double AxisRunToNormalFactor(const Vec3& n) {
  const double f = std::max({std::abs(n.x), std::abs(n.y), std::abs(n.z)});
  return f > 0 ? f : 1.0;
}

std::vector<float> FaceThickness(const TriangleMesh& mesh, const VoxelSet& set,
                                 std::span<const uint16_t> thickness, ThicknessMeasure measure) {
  const double reach = std::sqrt(3.0) / 2.0;
  const Dims& d = set.dims();
  std::vector<float> out(mesh.faces.size(), 0.0f);
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, mesh.faces.size(), 128),
      [&](const tbb::blocked_range<size_t>& r) {
        for (size_t f = r.begin(); f < r.end(); ++f) {
          const Triangle t = Corners(mesh, f);
          const Vec3 n = UnitNormal(t);
          int64_t lo[3], hi[3];
          for (int k = 0; k < 3; ++k) {
            const int64_t extent = k == 0 ? d.nx : (k == 1 ? d.ny : d.nz);
            lo[k] = std::max<int64_t>(0, std::ceil(std::min({t[0][k], t[1][k], t[2][k]}) - reach));
            hi[k] = std::min<int64_t>(extent - 1,
                                      std::floor(std::max({t[0][k], t[1][k], t[2][k]}) + reach));
          }
          double sum = 0;
          uint64_t count = 0;
          for (int64_t z = lo[2]; z <= hi[2]; ++z) {
            for (int64_t y = lo[1]; y <= hi[1]; ++y) {
              for (int64_t x = lo[0]; x <= hi[0]; ++x) {
                const Vec3 p(x, y, z);
                if (Norm2(n) > 0 && std::abs(Dot(p - t[0], n)) > reach) continue;
                if (PointTriangleDistance2(p, t) > reach * reach) continue;
                const int64_t i = set.Find(x, y, z);
                if (i < 0) continue;
                sum += thickness[i];
                ++count;
              }
            }
          }
          const double factor =
              measure == ThicknessMeasure::kNormal ? AxisRunToNormalFactor(n) : 1.0;
          out[f] = count > 0 ? static_cast<float>(factor * sum / count) : 0.0f;
        }
      });
  return out;
}

std::vector<int32_t> FaceLabels(const TriangleMesh& mesh, std::span<const int32_t> vertex_label) {
  std::vector<int32_t> out(mesh.faces.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const int32_t a = vertex_label[mesh.faces[f][0]], b = vertex_label[mesh.faces[f][1]],
                  c = vertex_label[mesh.faces[f][2]];
    if (a == b || a == c) {
      out[f] = a;
    } else if (b == c) {
      out[f] = b;
    } else {
      out[f] = std::min({a, b, c});
    }
  }
  return out;
}

}  // namespace sheetmesh
