// Grey volumes built in code with known apertures: sheets rendered by the share of each
// voxel they cover (partial volume), blurred by a Gaussian point spread and given noise at
// a contrast-to-noise ratio, in a rock with a band of void along one face (as the air
// around a core), so that the void's level shows in the histogram.
#ifndef SHEETMESH_TESTS_TESTING_GREY_PHANTOMS_H_
#define SHEETMESH_TESTS_TESTING_GREY_PHANTOMS_H_

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "common/types.h"
#include "worker/pipeline/voxel/grey_volume.h"

namespace sheetmesh::testing {

struct GreySheet {
  Vec3 center;
  Vec3 normal{0, 0, 1};
  Vec3 along{1, 0, 0};        // the aperture varies linearly along this in-plane axis
  double aperture = 1;        // at the centre
  double aperture_slope = 0;  // change per voxel along `along`
  double roughness = 0;       // amplitude of the mid-plane's waviness, voxels
  double Aperture(const Vec3& p) const {
    return std::max(0.0, aperture + aperture_slope * Dot(p - center, along));
  }
  // Signed distance of p from the (wavy) mid-surface, along the normal.
  double Offset(const Vec3& p) const {
    const Vec3 q = p - center;
    const double w = roughness * std::sin(0.21 * Dot(q, along)) *
                     std::cos(0.17 * Dot(q, Normalized(Cross(normal, along))));
    return Dot(q, normal) - w;
  }
};

struct GreyPhantomOptions {
  Dims dims{48, 48, 48};
  std::vector<GreySheet> sheets;
  double rock = 200, void_level = 40;
  double psf_sigma = 1.0;  // voxels
  double cnr = 10;         // contrast (rock - void) over the noise's σ
  int void_band = 10;      // voxels of void at x < void_band (a fifth of the box: about
                           // the air around a core in a square scan)
  unsigned seed = 1;
};

// The share of a unit cube whose points p have n.(p - centre) <= s, as a table over s.
class CubeShare {
 public:
  explicit CubeShare(const Vec3& n) {
    constexpr int k = 40;
    for (int i = 0; i < k; ++i)
      for (int j = 0; j < k; ++j)
        for (int l = 0; l < k; ++l) {
          const Vec3 p((i + 0.5) / k - 0.5, (j + 0.5) / k - 0.5, (l + 0.5) / k - 0.5);
          t_.push_back(Dot(p, n));
        }
    std::sort(t_.begin(), t_.end());
  }
  double Below(double s) const {
    return double(std::upper_bound(t_.begin(), t_.end(), s) - t_.begin()) / t_.size();
  }

 private:
  std::vector<double> t_;
};

inline void BlurAxis(std::vector<float>& v, const Dims& d, int axis, double sigma) {
  const int r = std::max(1, int(std::ceil(3 * sigma)));
  std::vector<double> k(2 * r + 1);
  double sum = 0;
  for (int i = -r; i <= r; ++i) sum += k[i + r] = std::exp(-0.5 * i * i / (sigma * sigma));
  for (double& x : k) x /= sum;
  const int64_t n[3] = {d.nx, d.ny, d.nz}, st[3] = {1, d.nx, d.nx * d.ny};
  const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
  std::vector<float> line(n[axis]);
  for (int64_t j = 0; j < n[a2]; ++j)
    for (int64_t i = 0; i < n[a1]; ++i) {
      const int64_t base = i * st[a1] + j * st[a2];
      for (int64_t t = 0; t < n[axis]; ++t) line[t] = v[base + t * st[axis]];
      for (int64_t t = 0; t < n[axis]; ++t) {
        double s = 0;
        for (int q = -r; q <= r; ++q)
          s += k[q + r] * line[std::clamp<int64_t>(t + q, 0, n[axis] - 1)];
        v[base + t * st[axis]] = float(s);
      }
    }
}

inline GreyVolume MakeGreyPhantom(const GreyPhantomOptions& o) {
  GreyVolume g;
  g.dims = o.dims;
  const Dims& d = o.dims;
  g.values.assign(d.num_voxels(), float(o.rock));
  std::vector<CubeShare> shares;
  for (const GreySheet& s : o.sheets) shares.emplace_back(Normalized(s.normal));
  for (int64_t z = 0; z < d.nz; ++z)
    for (int64_t y = 0; y < d.ny; ++y)
      for (int64_t x = 0; x < d.nx; ++x) {
        float& v = g.values[(z * d.ny + y) * d.nx + x];
        if (x < o.void_band) {
          v = float(o.void_level);
          continue;
        }
        double open = 0;
        const Vec3 p(x, y, z);
        for (size_t i = 0; i < o.sheets.size(); ++i) {
          const double off = o.sheets[i].Offset(p), h = 0.5 * o.sheets[i].Aperture(p);
          if (std::abs(off) > h + 1) continue;
          open += shares[i].Below(h - off) - shares[i].Below(-h - off);
        }
        v = float(o.rock - (o.rock - o.void_level) * std::min(1.0, open));
      }
  for (int axis = 0; axis < 3; ++axis) BlurAxis(g.values, d, axis, o.psf_sigma);
  std::mt19937 rng(o.seed);
  std::normal_distribution<double> noise(0, (o.rock - o.void_level) / o.cnr);
  for (float& v : g.values) v = float(v + noise(rng));
  return g;
}

}  // namespace sheetmesh::testing

#endif  // SHEETMESH_TESTS_TESTING_GREY_PHANTOMS_H_
