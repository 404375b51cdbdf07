#include "worker/pipeline/voxel/sheetness.h"

#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/status_macros.h"
#include "worker/pipeline/voxel/components.h"

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

// Convolves slices [0, n_slices) of `v` (nx × ny each) along `axis` with `k`, the border
// value repeated (along z the slab's first and last slices are its border).
void Convolve(std::vector<float>& v, const Dims& d, int64_t n_slices, int axis,
              const std::vector<double>& k) {
  const int r = static_cast<int>(k.size() / 2);
  const int64_t n[3] = {d.nx, d.ny, n_slices};
  const int64_t stride[3] = {1, d.nx, d.nx * d.ny};
  const int64_t len = n[axis], st = stride[axis];
  const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
  tbb::parallel_for(int64_t{0}, n[a2], [&](int64_t j) {
    // The line with its ends repeated r times: no clamp in the inner loop.
    std::vector<float> line(static_cast<size_t>(len + 2 * r));
    for (int64_t i = 0; i < n[a1]; ++i) {
      const int64_t base = i * stride[a1] + j * stride[a2];
      for (int64_t t = 0; t < len; ++t) line[t + r] = v[base + t * st];
      for (int q = 0; q < r; ++q) {
        line[q] = line[r];
        line[len + r + q] = line[len + r - 1];
      }
      for (int64_t t = 0; t < len; ++t) {
        double s = 0;
        for (int q = -r; q <= r; ++q) s += k[q + r] * line[t + r + q];
        v[base + t * st] = static_cast<float>(s);
      }
    }
  });
}

int KernelRadius(double sigma) { return std::max(1, static_cast<int>(std::ceil(3 * sigma))); }

// How far the valley check looks along the eigenvector, voxels.
double Reach(double sigma) { return std::max(1.0, 1.5 * sigma); }

// Slices beyond a core a scale's response needs: its kernel, the valley check's reach, the
// difference stencil and the trilinear sample.
int64_t Halo(double sigma) {
  return KernelRadius(sigma) + static_cast<int64_t>(std::ceil(Reach(sigma))) + 2;
}

// Grey levels smoothed at one scale on slices [z_lo, z_hi) of the volume (all of x and y):
// values by global coordinates, clamped to the volume as the whole volume's would be.
struct SmoothedSlab {
  const Dims* dims;
  int64_t z_lo = 0, z_hi = 0;
  std::vector<float> g;

  double At(int64_t x, int64_t y, int64_t z) const {
    x = std::clamp<int64_t>(x, 0, dims->nx - 1);
    y = std::clamp<int64_t>(y, 0, dims->ny - 1);
    z = std::clamp<int64_t>(z, 0, dims->nz - 1) - z_lo;
    return g[static_cast<size_t>((z * dims->ny + y) * dims->nx + x)];
  }
  double Sample(const Vec3& p) const {
    const double x = std::clamp(p.x, 0.0, double(dims->nx - 1));
    const double y = std::clamp(p.y, 0.0, double(dims->ny - 1));
    const double z = std::clamp(p.z, 0.0, double(dims->nz - 1));
    const int64_t x0 = int64_t(x), y0 = int64_t(y), z0 = int64_t(z);
    const double fx = x - x0, fy = y - y0, fz = z - z0;
    auto lerp = [](double a, double b, double t) { return a + (b - a) * t; };
    const double c00 = lerp(At(x0, y0, z0), At(x0 + 1, y0, z0), fx);
    const double c10 = lerp(At(x0, y0 + 1, z0), At(x0 + 1, y0 + 1, z0), fx);
    const double c01 = lerp(At(x0, y0, z0 + 1), At(x0 + 1, y0, z0 + 1), fx);
    const double c11 = lerp(At(x0, y0 + 1, z0 + 1), At(x0 + 1, y0 + 1, z0 + 1), fx);
    return lerp(lerp(c00, c10, fy), lerp(c01, c11, fy), fz);
  }
};

// The response of scale `s` on the core slices [z0, z1), from `grey` as floats on slices
// [e0, e1) (which hold [z0, z1) widened by Halo(s), clipped to the volume), into `response`
// (the core's voxels). A voxel whose Hessian is too small for s² |H| to reach `floor` is
// left at 0 without its eigenvectors (0: every voxel computed).
void ScaleResponse(const std::vector<float>& grey, int64_t e0, int64_t e1, int64_t z0, int64_t z1,
                   const Dims& d, double s, double floor, std::vector<float>* response) {
  SmoothedSlab slab{&d};
  slab.z_lo = std::max(e0, z0 - Halo(s));
  slab.z_hi = std::min(e1, z1 + Halo(s));
  const int64_t slice = d.nx * d.ny;
  slab.g.assign(grey.begin() + (slab.z_lo - e0) * slice, grey.begin() + (slab.z_hi - e0) * slice);
  const std::vector<double> k = Kernel(s);
  for (int axis = 0; axis < 3; ++axis) Convolve(slab.g, d, slab.z_hi - slab.z_lo, axis, k);
  const double norm = s * s, reach = Reach(s);
  const double floor2 = floor > 0 ? (floor / norm) * (floor / norm) : -1.0;
  response->assign(static_cast<size_t>((z1 - z0) * slice), 0.0f);
  tbb::parallel_for(z0, z1, [&](int64_t z) {
    for (int64_t y = 0; y < d.ny; ++y) {
      for (int64_t x = 0; x < d.nx; ++x) {
        auto at = [&](int64_t dx, int64_t dy, int64_t dz) {
          return slab.At(x + dx, y + dy, z + dz);
        };
        const double c = at(0, 0, 0);
        Eigen::Matrix3d h;
        h(0, 0) = at(1, 0, 0) - 2 * c + at(-1, 0, 0);
        h(1, 1) = at(0, 1, 0) - 2 * c + at(0, -1, 0);
        h(2, 2) = at(0, 0, 1) - 2 * c + at(0, 0, -1);
        h(0, 1) = h(1, 0) = 0.25 * (at(1, 1, 0) - at(1, -1, 0) - at(-1, 1, 0) + at(-1, -1, 0));
        h(0, 2) = h(2, 0) = 0.25 * (at(1, 0, 1) - at(1, 0, -1) - at(-1, 0, 1) + at(-1, 0, -1));
        h(1, 2) = h(2, 1) = 0.25 * (at(0, 1, 1) - at(0, 1, -1) - at(0, -1, 1) + at(0, -1, -1));
        // A valley's largest curvature is positive and outweighs the others: the trace is
        // positive (about half the voxels of noise are skipped here). The response is at
        // most s² times the largest eigenvalue, at most the Frobenius norm.
        if (!(h.trace() > 0) || h.squaredNorm() < floor2) continue;
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
        es.computeDirect(h, Eigen::ComputeEigenvectors);
        const Eigen::Vector3d e = es.eigenvalues();  // ascending
        // By magnitude: k3 the largest, k2 the next.
        const int k3 = std::abs(e[0]) > std::abs(e[2]) ? 0 : 2;
        const int o1 = k3 == 0 ? 1 : 0, o2 = k3 == 2 ? 1 : 2;
        const int k2 = std::abs(e[o1]) > std::abs(e[o2]) ? o1 : o2;
        if (!(e[k3] > 0)) continue;
        // A valley's floor: brighter on both sides along the eigenvector, by as much as its
        // curvature says (a Gaussian valley rises by 0.3-0.5 of λ d² at d = 1.5 σ). Beside a
        // step (the rock's edge against a pore) the curvature is as large, but one side
        // stays as dark or goes on darker: left out.
        const Eigen::Vector3d dir = es.eigenvectors().col(k3) * reach;
        const Vec3 p(x, y, z), step(dir[0], dir[1], dir[2]);
        const double plus = slab.Sample(p + step), minus = slab.Sample(p - step);
        if (std::min(plus, minus) - c >= 0.15 * e[k3] * reach * reach) {
          (*response)[static_cast<size_t>(((z - z0) * d.ny + y) * d.nx + x)] =
              static_cast<float>(norm * (e[k3] - std::abs(e[k2])));
        }
      }
    }
  });
}

// Slabs of core slices the volume is cut into: a slab's floats (its halo included) about
// `voxels`, its core at least twice its halo thick.
std::vector<std::pair<int64_t, int64_t>> Slabs(const Dims& d, int64_t halo, int64_t voxels) {
  const int64_t slice = std::max<int64_t>(1, d.nx * d.ny);
  const int64_t core = std::max<int64_t>(2 * halo, voxels / slice - 2 * halo);
  std::vector<std::pair<int64_t, int64_t>> out;
  for (int64_t z = 0; z < d.nz; z += core) out.emplace_back(z, std::min(d.nz, z + core));
  return out;
}

// What the two passes share: the grey levels of a slab (with the largest scale's halo) as
// floats.
struct SlabInput {
  int64_t e0 = 0, e1 = 0;
  std::vector<float> grey;
};

SlabInput ReadSlab(const GreyVolume& grey, int64_t z0, int64_t z1, int64_t halo) {
  SlabInput in;
  in.e0 = std::max<int64_t>(0, z0 - halo);
  in.e1 = std::min(grey.dims.nz, z1 + halo);
  in.grey.resize(static_cast<size_t>((in.e1 - in.e0) * grey.dims.nx * grey.dims.ny));
  grey.CopySlices(in.e0, in.e1 - in.e0, in.grey.data());
  return in;
}

// Each scale's noise unit: the median response over the voxels that respond at all, most of
// which are the rock's noise (a sheet's voxels are few). Noise answers the fine scales
// more, sheets the coarse ones: each scale in its own units. Measured on slabs spread over
// the volume holding about `sample` voxels (every slab of a volume that small; how many
// goes to `sampled`); `kept`, when every slab was measured, holds their responses
// [slab][scale] for the second pass.
std::vector<double> NoiseUnits(const GreyVolume& grey, const std::vector<double>& scales,
                               const std::vector<std::pair<int64_t, int64_t>>& slabs, int64_t halo,
                               int64_t sample, size_t* sampled,
                               std::vector<std::vector<std::vector<float>>>* kept) {
  const Dims& d = grey.dims;
  const int64_t slice = d.nx * d.ny;
  const int64_t per_slab = std::max<int64_t>(1, (slabs[0].second - slabs[0].first) * slice);
  const size_t wanted = static_cast<size_t>(std::clamp<int64_t>(
      (sample + per_slab - 1) / per_slab, 1, static_cast<int64_t>(slabs.size())));
  const bool all = wanted == slabs.size();
  *sampled = wanted;
  std::vector<std::vector<float>> positive(scales.size());
  if (all) kept->assign(slabs.size(), std::vector<std::vector<float>>(scales.size()));
  for (size_t i = 0; i < wanted; ++i) {
    // Evenly spread: slab i of `wanted` is slab (2i + 1) n / (2 wanted) of n.
    const size_t slab = all ? i : (2 * i + 1) * slabs.size() / (2 * wanted);
    const auto [z0, z1] = slabs[slab];
    const SlabInput in = ReadSlab(grey, z0, z1, halo);
    for (size_t k = 0; k < scales.size(); ++k) {
      std::vector<float> response;
      ScaleResponse(in.grey, in.e0, in.e1, z0, z1, d, scales[k], 0.0, &response);
      for (float v : response) {
        if (v > 0) positive[k].push_back(v);
      }
      if (all) (*kept)[slab][k] = std::move(response);
    }
  }
  std::vector<double> noise(scales.size(), 1e-12);
  for (size_t k = 0; k < scales.size(); ++k) {
    std::vector<float>& p = positive[k];
    if (p.empty()) continue;
    auto mid = p.begin() + p.size() / 2;
    std::nth_element(p.begin(), mid, p.end());
    noise[k] = std::max(noise[k], double(*mid));
  }
  return noise;
}

// Adds the runs of row (y, z) of `flags` (x fastest) where flags[x] holds `bit`.
void AddRuns(VoxelSet::Builder& b, const uint8_t* flags, int64_t nx, int64_t y, int64_t z,
             uint8_t bit) {
  for (int64_t x = 0; x < nx;) {
    if (!(flags[x] & bit)) {
      ++x;
      continue;
    }
    const int64_t x0 = x;
    while (x < nx && (flags[x] & bit)) ++x;
    b.AddRun(y, z, x0, x);
  }
}

}  // namespace

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
  if (options.slab_voxels <= 0 || options.noise_sample_voxels <= 0) {
    return absl::InvalidArgumentError("sheetness slab_voxels and noise_sample_voxels must be > 0");
  }
  if (!(options.low > 0) || !(options.low <= options.high)) {
    return absl::InvalidArgumentError(absl::StrCat("grey.low = ", options.low,
                                                   " and grey.high = ", options.high,
                                                   ": need 0 < low <= high (noise units)"));
  }
  const Dims& d = grey.dims;
  // Slab by slab: the floats of one slab at a time, the sheets' voxels kept as runs.
  int64_t halo = 0;
  for (double s : options.scales) halo = std::max(halo, Halo(s));
  const std::vector<std::pair<int64_t, int64_t>> slabs = Slabs(d, halo, options.slab_voxels);
  std::vector<std::vector<std::vector<float>>> kept;
  size_t sampled = 0;
  const std::vector<double> noise =
      NoiseUnits(grey, options.scales, slabs, halo, options.noise_sample_voxels, &sampled, &kept);
  SM_RETURN_IF_ERROR(progress.Update(kept.empty() ? 0.2 : 0.7, "sheetness"));
  const float high = static_cast<float>(options.high), low = static_cast<float>(options.low);
  // The voxels above `low` (bit 1) and those above `high` too (bit 2).
  VoxelSet::Builder above_low(d), above_high(d);
  const int64_t slice = d.nx * d.ny;
  std::vector<float> best;
  std::vector<uint8_t> flags;
  for (size_t i = 0; i < slabs.size(); ++i) {
    const auto [z0, z1] = slabs[i];
    best.assign(static_cast<size_t>((z1 - z0) * slice), 0.0f);
    auto take = [&](const std::vector<float>& response, size_t k) {
      const float inverse = static_cast<float>(1.0 / noise[k]);
      for (size_t j = 0; j < best.size(); ++j) best[j] = std::max(best[j], response[j] * inverse);
    };
    if (!kept.empty()) {
      for (size_t k = 0; k < options.scales.size(); ++k) take(kept[i][k], k);
      kept[i].clear();
    } else {
      const SlabInput in = ReadSlab(grey, z0, z1, halo);
      std::vector<float> response;
      for (size_t k = 0; k < options.scales.size(); ++k) {
        // Only what could reach `low` matters here: the eigenvectors of the rest are skipped.
        ScaleResponse(in.grey, in.e0, in.e1, z0, z1, d, options.scales[k], options.low * noise[k],
                      &response);
        take(response, k);
      }
    }
    flags.assign(best.size(), 0);
    for (size_t j = 0; j < best.size(); ++j) {
      if (best[j] >= low && best[j] > 0) flags[j] = best[j] >= high ? 3 : 1;
    }
    for (int64_t z = z0; z < z1; ++z) {
      for (int64_t y = 0; y < d.ny; ++y) {
        const uint8_t* row = flags.data() + ((z - z0) * d.ny + y) * d.nx;
        AddRuns(above_low, row, d.nx, y, z, 1);
        AddRuns(above_high, row, d.nx, y, z, 2);
      }
    }
    SM_RETURN_IF_ERROR(progress.Update((kept.empty() ? 0.2 : 0.7) +
                                       (kept.empty() ? 0.7 : 0.2) * double(i + 1) / slabs.size()));
  }
  const VoxelSet candidates = std::move(above_low).Build();
  const VoxelSet seeds = std::move(above_high).Build();
  // Hysteresis: the face-connected pieces of the voxels above `low` that hold a seed.
  SM_ASSIGN_OR_RETURN(const Components pieces, LabelComponents(candidates, Connectivity::k6));
  std::vector<uint8_t> seeded(pieces.count(), 0);
  seeds.ForEachRun([&](int32_t y, int32_t z, const Run& run, uint64_t) {
    // A run of seeds lies within one run of candidates: the last starting at or before it.
    const std::span<const Run> row = candidates.RowRuns(y, z);
    const auto it = std::upper_bound(row.begin(), row.end(), run.x0,
                                     [](int32_t x, const Run& c) { return x < c.x0; });
    seeded[pieces.run_label[candidates.RowBegin(candidates.RowId(y, z)) + (it - row.begin()) - 1]] =
        1;
  });
  std::vector<uint8_t> keep(candidates.size(), 0);
  for (int64_t r = 0; r < candidates.num_runs(); ++r) {
    if (!seeded[pieces.run_label[r]]) continue;
    const uint64_t f = candidates.RunFirstIndex(r);
    std::fill(keep.begin() + f, keep.begin() + f + candidates.run(r).length(), 1);
  }
  VoxelSet sheets = candidates.Filter(keep);
  if (stats) {
    stats->noise = noise;
    stats->seeds = seeds.size();
    stats->slabs = slabs.size();
    stats->sampled_slabs = sampled;
    stats->detected = sheets.size();
    stats->seconds = absl::ToDoubleSeconds(absl::Now() - start);
  }
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return sheets;
}

}  // namespace sheetmesh
