#include "worker/pipeline/surface/prism_columns.h"

#include <algorithm>
#include <cmath>

#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {

void ColumnOf(const TriangleMesh& mesh, size_t f, const VoxelSet& set, double pad,
              std::vector<ColumnVoxel>* column) {
  column->clear();
  const Dims& d = set.dims();
  const Triangle t = Corners(mesh, f);
  const Vec3 n = UnitNormal(t);
  if (Norm2(n) == 0 || !(pad > 0)) return;
  // Barycentric coordinates of the projection of p along n are affine in p:
  // v = A·(p - t0), w = B·(p - t0), u = 1 - v - w (as ProjectBarycentric computes them).
  const Vec3 e1 = t[1] - t[0], e2 = t[2] - t[0];
  const double g11 = Dot(e1, e1), g12 = Dot(e1, e2), g22 = Dot(e2, e2);
  const double det = g11 * g22 - g12 * g12;
  if (!(std::abs(det) > 1e-18 * (g11 * g22 + 1e-300))) return;
  const Vec3 A = (e1 * g22 - e2 * g12) * (1.0 / det), B = (e2 * g11 - e1 * g12) * (1.0 / det);
  // Walk the prism along the axis k nearest its normal: for each cell (i, j) of the other
  // two axes within the prism's box, the k-range where all four affine conditions hold.
  const int k = std::abs(n.x) >= std::abs(n.y) && std::abs(n.x) >= std::abs(n.z)
                    ? 0
                    : (std::abs(n.y) >= std::abs(n.z) ? 1 : 2);
  const int ia = (k + 1) % 3, ja = (k + 2) % 3;
  const int64_t extent[3] = {d.nx, d.ny, d.nz};
  auto range = [&](int axis, int64_t* lo, int64_t* hi) {
    const double reach = pad * std::abs(n[axis]);
    *lo = std::max<int64_t>(0, static_cast<int64_t>(std::ceil(
                                   std::min({t[0][axis], t[1][axis], t[2][axis]}) - reach - 1e-9)));
    *hi = std::min<int64_t>(extent[axis] - 1,
                            static_cast<int64_t>(std::floor(
                                std::max({t[0][axis], t[1][axis], t[2][axis]}) + reach + 1e-9)));
  };
  int64_t ilo, ihi, jlo, jhi;
  range(ia, &ilo, &ihi);
  range(ja, &jlo, &jhi);
  constexpr double kEps = 1e-9;
  for (int64_t i = ilo; i <= ihi; ++i) {
    for (int64_t j = jlo; j <= jhi; ++j) {
      // Each condition f0 + c f1 >= 0 (f1 the coefficient of the k coordinate c) bounds c.
      Vec3 q0;
      q0[ia] = double(i) - t[0][ia];
      q0[ja] = double(j) - t[0][ja];
      q0[k] = -t[0][k];
      double clo = 0, chi = double(extent[k] - 1);
      auto bound = [&](double f0, double f1) {
        if (std::abs(f1) < 1e-15) {
          if (f0 < 0) chi = -1;  // never
        } else if (f1 > 0) {
          clo = std::max(clo, -f0 / f1);
        } else {
          chi = std::min(chi, -f0 / f1);
        }
      };
      const double v0 = Dot(A, q0), w0 = Dot(B, q0), dist0 = Dot(n, q0);
      bound(v0 + kEps, A[k]);
      bound(w0 + kEps, B[k]);
      bound(1 - v0 - w0 + kEps, -A[k] - B[k]);
      bound(pad - dist0, -n[k]);
      bound(pad + dist0, n[k]);
      if (clo > chi) continue;
      for (int64_t c = static_cast<int64_t>(std::ceil(clo - kEps));
           c <= static_cast<int64_t>(std::floor(chi + kEps)); ++c) {
        const Vec3 q(q0[0] + (k == 0 ? double(c) : 0.0), q0[1] + (k == 1 ? double(c) : 0.0),
                     q0[2] + (k == 2 ? double(c) : 0.0));
        const double v = Dot(A, q), w = Dot(B, q), dist = std::abs(Dot(n, q));
        if (v < -kEps || w < -kEps || 1 - v - w < -kEps || dist > pad) continue;
        int64_t xyz[3];
        xyz[k] = c;
        xyz[ia] = i;
        xyz[ja] = j;
        const int64_t at = set.Find(xyz[0], xyz[1], xyz[2]);
        column->push_back(
            {dist, at >= 0 ? uint64_t(at) : uint64_t((xyz[2] * d.ny + xyz[1]) * d.nx + xyz[0]),
             at >= 0});
      }
    }
  }
  std::sort(column->begin(), column->end());
}

}  // namespace sheetmesh
