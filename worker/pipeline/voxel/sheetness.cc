#include "worker/pipeline/voxel/sheetness.h"

#include <tbb/enumerable_thread_specific.h>
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
std::vector<float> Kernel(double sigma) {
  const int r = std::max(1, static_cast<int>(std::ceil(3 * sigma)));
  std::vector<double> k(2 * r + 1);
  double sum = 0;
  for (int i = -r; i <= r; ++i) sum += k[i + r] = std::exp(-0.5 * i * i / (sigma * sigma));
  std::vector<float> out(k.size());
  for (size_t i = 0; i < k.size(); ++i) out[i] = static_cast<float>(k[i] / sum);
  return out;
}

int KernelRadius(double sigma) { return std::max(1, static_cast<int>(std::ceil(3 * sigma))); }

// How far the valley check looks along the eigenvector, voxels.
double Reach(double sigma) { return std::max(1.0, 1.5 * sigma); }

// Smoothed slices beyond a core a scale's response needs: the valley check's reach, the
// difference stencil and the trilinear sample (the smoothing reads the volume's own slices
// a kernel's radius further).
int64_t Halo(double sigma) { return static_cast<int64_t>(std::ceil(Reach(sigma))) + 2; }

// out[x] = Σ_q k[q] rows[q][x] over a row of n: the inner loop runs along x, contiguous.
void WeightedRows(const std::vector<const float*>& rows, const std::vector<float>& k, int64_t n,
                  float* out) {
  std::fill(out, out + n, 0.0f);
  for (size_t q = 0; q < k.size(); ++q) {
    const float w = k[q];
    const float* row = rows[q];
    for (int64_t x = 0; x < n; ++x) out[x] += w * row[x];
  }
}

// The grey levels of slices [z_lo, z_hi) smoothed by the separable Gaussian `k` into
// `out`, the border value repeated at the volume's faces: along z and y whole rows at a
// time, along x a padded line. Each smoothed voxel reads the volume's slices within the
// kernel's radius of it (clamped to the volume, not to the slab), so a slab's voxels are
// the whole volume's.
void Smooth(const GreyVolume& grey, int64_t z_lo, int64_t z_hi, const std::vector<float>& k,
            std::vector<float>* out) {
  const Dims& d = grey.dims;
  const int r = static_cast<int>(k.size() / 2);
  const int64_t slice = d.nx * d.ny;
  out->resize(static_cast<size_t>((z_hi - z_lo) * slice));
  // A slice's worth of floats per thread, for the pass along y.
  tbb::enumerable_thread_specific<std::vector<float>> copies;
  tbb::parallel_for(z_lo, z_hi, [&](int64_t z) {
    std::vector<float>& source = copies.local();
    source.resize(std::max<size_t>(static_cast<size_t>(slice), k.size() * d.nx));
    float* dst = out->data() + (z - z_lo) * slice;
    std::vector<const float*> rows(k.size());
    // Along z: the volume's rows within the radius as floats, a row at a time.
    for (int64_t y = 0; y < d.ny; ++y) {
      for (int q = -r; q <= r; ++q) {
        const int64_t zz = std::clamp<int64_t>(z + q, 0, d.nz - 1);
        float* buffer = source.data() + (q + r) * d.nx;
        grey.CopyValues(static_cast<size_t>((zz * d.ny + y) * d.nx), static_cast<size_t>(d.nx),
                        buffer);
        rows[q + r] = buffer;
      }
      WeightedRows(rows, k, d.nx, dst + y * d.nx);
    }
    // Along y, from a copy of the slice.
    std::copy(dst, dst + slice, source.begin());
    for (int64_t y = 0; y < d.ny; ++y) {
      for (int q = -r; q <= r; ++q) {
        rows[q + r] = source.data() + std::clamp<int64_t>(y + q, 0, d.ny - 1) * d.nx;
      }
      WeightedRows(rows, k, d.nx, dst + y * d.nx);
    }
    // Along x, a line at a time with its ends repeated r times: row q of the sum is the
    // line shifted by q.
    std::vector<float> line(static_cast<size_t>(d.nx + 2 * r));
    for (int q = 0; q <= 2 * r; ++q) rows[q] = line.data() + q;
    for (int64_t y = 0; y < d.ny; ++y) {
      float* row = dst + y * d.nx;
      std::copy(row, row + d.nx, line.begin() + r);
      std::fill(line.begin(), line.begin() + r, row[0]);
      std::fill(line.end() - r, line.end(), row[d.nx - 1]);
      WeightedRows(rows, k, d.nx, row);
    }
  });
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

// Where a scale's responses go for the core slices [z0, z1): raw into `out` (zeros where
// none), or, with `into_best`, each times `unit` into the running maximum `out`.
struct ResponseSink {
  float* out = nullptr;
  bool into_best = false;
  float unit = 1;
};

// The response of scale `s` on the core slices [z0, z1) of `grey`. A voxel whose Hessian
// is too small for s² |H| to reach `floor` gives none, without its eigenvectors (0: every
// voxel computed). `scratch` lends the smoothed slab its memory (kept between calls: a new
// buffer of that size costs its pages' first touch each time).
void ScaleResponse(const GreyVolume& grey, int64_t z0, int64_t z1, double s, double floor,
                   const ResponseSink& sink, std::vector<float>* scratch) {
  const Dims& d = grey.dims;
  SmoothedSlab slab{&d};
  slab.g.swap(*scratch);
  slab.z_lo = std::max<int64_t>(0, z0 - Halo(s));
  slab.z_hi = std::min(d.nz, z1 + Halo(s));
  Smooth(grey, slab.z_lo, slab.z_hi, Kernel(s), &slab.g);
  const double norm = s * s, reach = Reach(s);
  const double least = floor / norm;  // the largest eigenvalue a response of `floor` needs
  const int64_t sx = 1, sy = d.nx, sz = d.nx * d.ny;
  if (!sink.into_best) std::fill(sink.out, sink.out + (z1 - z0) * sz, 0.0f);
  tbb::parallel_for(z0, z1, [&](int64_t z) {
    const bool z_inside = z > 0 && z + 1 < d.nz;
    for (int64_t y = 0; y < d.ny; ++y) {
      const bool row_inside = z_inside && y > 0 && y + 1 < d.ny;
      const float* row = slab.g.data() + ((z - slab.z_lo) * d.ny + y) * d.nx;
      for (int64_t x = 0; x < d.nx; ++x) {
        Eigen::Matrix3d h;
        double c;
        if (row_inside && x > 0 && x + 1 < d.nx) {
          // Inside the volume: the neighbours by their offsets.
          const float* p = row + x;
          c = p[0];
          h(0, 0) = p[sx] - 2 * c + p[-sx];
          h(1, 1) = p[sy] - 2 * c + p[-sy];
          h(2, 2) = p[sz] - 2 * c + p[-sz];
          h(0, 1) = 0.25 * (double(p[sx + sy]) - p[sx - sy] - p[-sx + sy] + p[-sx - sy]);
          h(0, 2) = 0.25 * (double(p[sx + sz]) - p[sx - sz] - p[-sx + sz] + p[-sx - sz]);
          h(1, 2) = 0.25 * (double(p[sy + sz]) - p[sy - sz] - p[-sy + sz] + p[-sy - sz]);
        } else {
          auto at = [&](int64_t dx, int64_t dy, int64_t dz) {
            return slab.At(x + dx, y + dy, z + dz);
          };
          c = at(0, 0, 0);
          h(0, 0) = at(1, 0, 0) - 2 * c + at(-1, 0, 0);
          h(1, 1) = at(0, 1, 0) - 2 * c + at(0, -1, 0);
          h(2, 2) = at(0, 0, 1) - 2 * c + at(0, 0, -1);
          h(0, 1) = 0.25 * (at(1, 1, 0) - at(1, -1, 0) - at(-1, 1, 0) + at(-1, -1, 0));
          h(0, 2) = 0.25 * (at(1, 0, 1) - at(1, 0, -1) - at(-1, 0, 1) + at(-1, 0, -1));
          h(1, 2) = 0.25 * (at(0, 1, 1) - at(0, 1, -1) - at(0, -1, 1) + at(0, -1, -1));
        }
        h(1, 0) = h(0, 1);
        h(2, 0) = h(0, 2);
        h(2, 1) = h(1, 2);
        // A valley's largest curvature is positive and outweighs the others: the trace is
        // positive (about half the voxels of noise are skipped here).
        if (!(h.trace() > 0)) continue;
        // The response is at most s² times the largest eigenvalue: where every eigenvalue is
        // at most `least`, (least I − H) is positive semidefinite (its principal minors are
        // not negative) and no response reaches `floor`.
        if (least > 0) {
          const double a = least - h(0, 0), b = least - h(1, 1), c2 = least - h(2, 2);
          const double ab = h(0, 1), ac = h(0, 2), bc = h(1, 2);
          if (a >= 0 && b >= 0 && c2 >= 0 && a * b >= ab * ab && a * c2 >= ac * ac &&
              b * c2 >= bc * bc &&
              a * (b * c2 - bc * bc) - ab * (ab * c2 - bc * ac) + ac * (ab * bc - b * ac) >= 0) {
            continue;
          }
        }
        // The eigenvalues first; the vectors only where the response counts.
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
        es.computeDirect(h, Eigen::EigenvaluesOnly);
        const Eigen::Vector3d e = es.eigenvalues();  // ascending
        // By magnitude: k3 the largest, k2 the next.
        const int k3 = std::abs(e[0]) > std::abs(e[2]) ? 0 : 2;
        const int o1 = k3 == 0 ? 1 : 0, o2 = k3 == 2 ? 1 : 2;
        const int k2 = std::abs(e[o1]) > std::abs(e[o2]) ? o1 : o2;
        if (!(e[k3] > 0)) continue;
        const float v = static_cast<float>(norm * (e[k3] - std::abs(e[k2])));
        if (!(v > 0) || v < floor) continue;
        es.computeDirect(h, Eigen::ComputeEigenvectors);
        // A valley's floor: brighter on both sides along the eigenvector, by as much as its
        // curvature says (a Gaussian valley rises by 0.3-0.5 of λ d² at d = 1.5 σ). Beside a
        // step (the rock's edge against a pore) the curvature is as large, but one side
        // stays as dark or goes on darker: left out.
        const Eigen::Vector3d dir = es.eigenvectors().col(k3) * reach;
        const Vec3 p(x, y, z), step(dir[0], dir[1], dir[2]);
        const double plus = slab.Sample(p + step), minus = slab.Sample(p - step);
        if (std::min(plus, minus) - c < 0.15 * e[k3] * reach * reach) continue;
        float& o = sink.out[((z - z0) * d.ny + y) * d.nx + x];
        o = sink.into_best ? std::max(o, v * sink.unit) : v;
      }
    }
  });
  scratch->swap(slab.g);
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

// Each scale's noise unit: the median response over the voxels that respond at all, most of
// which are the rock's noise (a sheet's voxels are few). Noise answers the fine scales
// more, sheets the coarse ones: each scale in its own units. Measured on about `planes`
// slices (every slice when that is all of them): blocks of up to 4 consecutive slices
// spread evenly through the volume, each smoothed with only the slices its responses read.
// The slices measured go to `measured`.
std::vector<double> NoiseUnits(const GreyVolume& grey, const std::vector<double>& scales,
                               int64_t planes, std::vector<float>* scratch, int64_t* measured,
                               const Progress& progress, absl::Status* status) {
  const Dims& d = grey.dims;
  std::vector<std::pair<int64_t, int64_t>> blocks;
  if (planes >= d.nz) {
    blocks.emplace_back(0, d.nz);
  } else {
    const int64_t count = (planes + 3) / 4, per = (planes + count - 1) / count;
    for (int64_t i = 0; i < count; ++i) {
      const int64_t z0 =
          std::clamp<int64_t>((2 * i + 1) * d.nz / (2 * count) - per / 2, 0, d.nz - per);
      blocks.emplace_back(z0, z0 + per);
    }
  }
  *measured = 0;
  std::vector<std::vector<float>> positive(scales.size());
  std::vector<float> response;
  for (size_t i = 0; i < blocks.size() && status->ok(); ++i) {
    const auto [z0, z1] = blocks[i];
    *measured += z1 - z0;
    response.resize(static_cast<size_t>((z1 - z0) * d.nx * d.ny));
    for (size_t k = 0; k < scales.size(); ++k) {
      ScaleResponse(grey, z0, z1, scales[k], 0.0, {response.data()}, scratch);
      for (float v : response) {
        if (v > 0) positive[k].push_back(v);
      }
    }
    *status = progress.Update(double(i + 1) / blocks.size());
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
  // The noise units from slices holding about noise_sample_voxels voxels.
  const int64_t slice = d.nx * d.ny;
  const int64_t planes =
      std::clamp<int64_t>((options.noise_sample_voxels + slice - 1) / slice, 1, d.nz);
  absl::Status status;
  std::vector<float> scratch;
  int64_t measured = 0;
  const std::vector<double> noise =
      NoiseUnits(grey, options.scales, planes, &scratch, &measured, progress.Sub(0, 0.3), &status);
  SM_RETURN_IF_ERROR(status);
  const float high = static_cast<float>(options.high), low = static_cast<float>(options.low);
  // The voxels above `low` (bit 1) and those above `high` too (bit 2).
  VoxelSet::Builder above_low(d), above_high(d);
  std::vector<float> best;
  std::vector<uint8_t> flags;
  for (size_t i = 0; i < slabs.size(); ++i) {
    const auto [z0, z1] = slabs[i];
    best.assign(static_cast<size_t>((z1 - z0) * slice), 0.0f);
    for (size_t k = 0; k < options.scales.size(); ++k) {
      // Only what could reach `low` matters here: the eigenvectors of the rest are skipped.
      ScaleResponse(grey, z0, z1, options.scales[k], options.low * noise[k],
                    {best.data(), true, static_cast<float>(1.0 / noise[k])}, &scratch);
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
    SM_RETURN_IF_ERROR(progress.Update(0.3 + 0.6 * double(i + 1) / slabs.size()));
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
    stats->noise_slices = measured;
    stats->detected = sheets.size();
    stats->seconds = absl::ToDoubleSeconds(absl::Now() - start);
  }
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return sheets;
}

}  // namespace sheetmesh
