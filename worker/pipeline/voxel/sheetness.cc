#include "worker/pipeline/voxel/sheetness.h"

#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <deque>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/status_macros.h"

namespace sheetmesh {
namespace {

// A 1-D Gaussian of σ, truncated at 3σ, summing to 1.
std::vector<double> Kernel(double sigma) {
  const int r = std::max(1, static_cast<int>(std::ceil(3 * sigma)));
  std::vector<double> k(2 * r + 1);
  double sum = 0;
  for (int i = -r; i <= r; ++i) sum += k[i + r] = std::exp(-0.5 * i * i / (sigma * sigma));
  for (double& v : k) v /= sum;
  return k;
}

// Convolves `v` (dims d) along `axis` with `k`, the border value repeated.
void Convolve(std::vector<float>& v, const Dims& d, int axis, const std::vector<double>& k) {
  const int r = static_cast<int>(k.size() / 2);
  const int64_t n[3] = {d.nx, d.ny, d.nz};
  const int64_t stride[3] = {1, d.nx, d.nx * d.ny};
  const int64_t len = n[axis], st = stride[axis];
  const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
  tbb::parallel_for(int64_t{0}, n[a2], [&](int64_t j) {
    std::vector<float> line(static_cast<size_t>(len)), out(static_cast<size_t>(len));
    for (int64_t i = 0; i < n[a1]; ++i) {
      const int64_t base = i * stride[a1] + j * stride[a2];
      for (int64_t t = 0; t < len; ++t) line[t] = v[base + t * st];
      for (int64_t t = 0; t < len; ++t) {
        double s = 0;
        for (int q = -r; q <= r; ++q) s += k[q + r] * line[std::clamp<int64_t>(t + q, 0, len - 1)];
        out[t] = static_cast<float>(s);
      }
      for (int64_t t = 0; t < len; ++t) v[base + t * st] = out[t];
    }
  });
}

}  // namespace

std::vector<float> Sheetness(const GreyVolume& grey, const std::vector<double>& scales,
                             std::vector<double>* noise_per_scale) {
  const Dims& d = grey.dims;
  std::vector<float> best(grey.values.size(), 0.0f);
  if (noise_per_scale) noise_per_scale->clear();
  std::vector<float> response(grey.values.size());
  for (double s : scales) {
    GreyVolume smoothed{d, grey.values};
    std::vector<float>& g = smoothed.values;
    const std::vector<double> k = Kernel(s);
    for (int axis = 0; axis < 3; ++axis) Convolve(g, d, axis, k);
    auto at = [&](int64_t x, int64_t y, int64_t z) {
      x = std::clamp<int64_t>(x, 0, d.nx - 1);
      y = std::clamp<int64_t>(y, 0, d.ny - 1);
      z = std::clamp<int64_t>(z, 0, d.nz - 1);
      return double(g[static_cast<size_t>((z * d.ny + y) * d.nx + x)]);
    };
    const double norm = s * s;
    tbb::parallel_for(int64_t{0}, d.nz, [&](int64_t z) {
      for (int64_t y = 0; y < d.ny; ++y) {
        for (int64_t x = 0; x < d.nx; ++x) {
          const double c = at(x, y, z);
          Eigen::Matrix3d h;
          h(0, 0) = at(x + 1, y, z) - 2 * c + at(x - 1, y, z);
          h(1, 1) = at(x, y + 1, z) - 2 * c + at(x, y - 1, z);
          h(2, 2) = at(x, y, z + 1) - 2 * c + at(x, y, z - 1);
          h(0, 1) = h(1, 0) = 0.25 * (at(x + 1, y + 1, z) - at(x + 1, y - 1, z) -
                                      at(x - 1, y + 1, z) + at(x - 1, y - 1, z));
          h(0, 2) = h(2, 0) = 0.25 * (at(x + 1, y, z + 1) - at(x + 1, y, z - 1) -
                                      at(x - 1, y, z + 1) + at(x - 1, y, z - 1));
          h(1, 2) = h(2, 1) = 0.25 * (at(x, y + 1, z + 1) - at(x, y + 1, z - 1) -
                                      at(x, y - 1, z + 1) + at(x, y - 1, z - 1));
          // A valley's largest curvature is positive and outweighs the others: the trace is
          // positive (about half the voxels of noise are skipped here).
          if (!(h.trace() > 0)) {
            response[static_cast<size_t>((z * d.ny + y) * d.nx + x)] = 0.0f;
            continue;
          }
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
          es.computeDirect(h, Eigen::ComputeEigenvectors);
          const Eigen::Vector3d e = es.eigenvalues();  // ascending
          // By magnitude: k3 the largest, k2 the next.
          const int k3 = std::abs(e[0]) > std::abs(e[2]) ? 0 : 2;
          const int o1 = k3 == 0 ? 1 : 0, o2 = k3 == 2 ? 1 : 2;
          const int k2 = std::abs(e[o1]) > std::abs(e[o2]) ? o1 : o2;
          double v = 0;
          if (e[k3] > 0) {
            // A valley's floor: brighter on both sides along the eigenvector, by as much as
            // its curvature says (a Gaussian valley rises by 0.3-0.5 of λ d² at d = 1.5 σ).
            // Beside a step (the rock's edge against a pore) the curvature is as large, but
            // one side stays as dark or goes on darker: left out.
            const double reach = std::max(1.0, 1.5 * s);
            const Eigen::Vector3d dir = es.eigenvectors().col(k3) * reach;
            const Vec3 p(x, y, z), step(dir[0], dir[1], dir[2]);
            const double plus = smoothed.Sample(p + step), minus = smoothed.Sample(p - step);
            if (std::min(plus, minus) - c >= 0.15 * e[k3] * reach * reach) {
              v = norm * (e[k3] - std::abs(e[k2]));
            }
          }
          response[static_cast<size_t>((z * d.ny + y) * d.nx + x)] = static_cast<float>(v);
        }
      }
    });
    // In units of this scale's noise: the median response over the voxels that respond
    // at all, most of which are the rock's noise (a sheet's voxels are few). Noise answers
    // the fine scales more, sheets the coarse ones: each scale in its own units.
    std::vector<float> positive;
    for (float v : response) {
      if (v > 0) positive.push_back(v);
    }
    double noise = 1e-12;
    if (!positive.empty()) {
      auto mid = positive.begin() + positive.size() / 2;
      std::nth_element(positive.begin(), mid, positive.end());
      noise = std::max(noise, double(*mid));
    }
    if (noise_per_scale) noise_per_scale->push_back(noise);
    const float inverse = static_cast<float>(1.0 / noise);
    for (size_t i = 0; i < best.size(); ++i) best[i] = std::max(best[i], response[i] * inverse);
  }
  return best;
}

absl::StatusOr<VoxelSet> DetectSheets(const GreyVolume& grey, const SheetnessOptions& options,
                                      SheetnessStats* stats, const Progress& progress) {
  const absl::Time start = absl::Now();
  if (options.scales.empty()) {
    return absl::InvalidArgumentError("grey.scales is empty: sheetness needs at least one scale");
  }
  for (double s : options.scales) {
    if (!(s > 0 && s <= 16)) {
      return absl::InvalidArgumentError(
          absl::StrCat("grey.scales holds ", s, ": each scale must be in (0, 16] voxels"));
    }
  }
  if (!(options.low > 0) || !(options.low <= options.high)) {
    return absl::InvalidArgumentError(absl::StrCat("grey.low = ", options.low,
                                                   " and grey.high = ", options.high,
                                                   ": need 0 < low <= high (noise units)"));
  }
  const Dims& d = grey.dims;
  std::vector<double> noise;
  const std::vector<float> sheetness = Sheetness(grey, options.scales, &noise);
  SM_RETURN_IF_ERROR(progress.Update(0.7, "sheetness"));
  const float high = static_cast<float>(options.high), low = static_cast<float>(options.low);
  // Hysteresis: breadth-first from the seeds through face neighbours above `low`.
  std::vector<uint8_t> in(sheetness.size(), 0);
  std::deque<int64_t> queue;
  uint64_t seeds = 0;
  for (size_t i = 0; i < sheetness.size(); ++i) {
    if (sheetness[i] >= high && sheetness[i] > 0) {
      in[i] = 1;
      queue.push_back(static_cast<int64_t>(i));
      ++seeds;
    }
  }
  const int64_t sx = 1, sy = d.nx, sz = d.nx * d.ny;
  while (!queue.empty()) {
    const int64_t i = queue.front();
    queue.pop_front();
    const int64_t x = i % d.nx, y = (i / d.nx) % d.ny, z = i / sz;
    const int64_t nb[6][2] = {{x > 0, -sx},       {x + 1 < d.nx, sx}, {y > 0, -sy},
                              {y + 1 < d.ny, sy}, {z > 0, -sz},       {z + 1 < d.nz, sz}};
    for (const auto& [ok, step] : nb) {
      if (!ok) continue;
      const int64_t j = i + step;
      if (!in[j] && sheetness[j] >= low && sheetness[j] > 0) {
        in[j] = 1;
        queue.push_back(j);
      }
    }
  }
  VoxelSet::Builder b(d);
  uint64_t detected = 0;
  for (int64_t z = 0; z < d.nz; ++z)
    for (int64_t y = 0; y < d.ny; ++y)
      for (int64_t x = 0; x < d.nx; ++x)
        if (in[static_cast<size_t>((z * d.ny + y) * d.nx + x)]) {
          b.AddVoxel(x, y, z);
          ++detected;
        }
  if (stats) {
    stats->noise = noise;
    stats->seeds = seeds;
    stats->detected = detected;
    stats->seconds = absl::ToDoubleSeconds(absl::Now() - start);
  }
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return std::move(b).Build();
}

}  // namespace sheetmesh
