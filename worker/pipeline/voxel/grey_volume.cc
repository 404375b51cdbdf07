#include "worker/pipeline/voxel/grey_volume.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <set>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "common/status_macros.h"

namespace sheetmesh {

double GreyVolume::Sample(const Vec3& p) const {
  auto clamp = [](double v, int64_t n) { return std::clamp(v, 0.0, double(n - 1)); };
  const double x = clamp(p.x, dims.nx), y = clamp(p.y, dims.ny), z = clamp(p.z, dims.nz);
  const int64_t x0 = std::min<int64_t>(int64_t(x), dims.nx - 1),
                y0 = std::min<int64_t>(int64_t(y), dims.ny - 1),
                z0 = std::min<int64_t>(int64_t(z), dims.nz - 1);
  const int64_t x1 = std::min(x0 + 1, dims.nx - 1), y1 = std::min(y0 + 1, dims.ny - 1),
                z1 = std::min(z0 + 1, dims.nz - 1);
  const double fx = x - x0, fy = y - y0, fz = z - z0;
  auto lerp = [](double a, double b, double t) { return a + (b - a) * t; };
  const double c00 = lerp(At(x0, y0, z0), At(x1, y0, z0), fx);
  const double c10 = lerp(At(x0, y1, z0), At(x1, y1, z0), fx);
  const double c01 = lerp(At(x0, y0, z1), At(x1, y0, z1), fx);
  const double c11 = lerp(At(x0, y1, z1), At(x1, y1, z1), fx);
  return lerp(lerp(c00, c10, fy), lerp(c01, c11, fy), fz);
}

void GreyVolume::CopyValues(size_t begin, size_t n, float* out) const {
  if (!values8.empty()) {
    std::copy(values8.begin() + begin, values8.begin() + begin + n, out);
  } else if (!values16.empty()) {
    std::copy(values16.begin() + begin, values16.begin() + begin + n, out);
  } else {
    std::copy(values.begin() + begin, values.begin() + begin + n, out);
  }
}

absl::StatusOr<GreyVolume> ReadGreyVolume(VolumeSource& source, const VolumeLimits& limits,
                                          const Progress& progress) {
  const VolumeInfo& info = source.info();
  GreyVolume g;
  g.dims = info.dims;
  const int64_t n = g.dims.num_voxels();
  const int bytes = BytesPerVoxel(info.dtype);
  SM_RETURN_IF_ERROR(CheckAllocation(
      n * bytes, limits, absl::StrCat("the grey levels (", DTypeName(info.dtype), ")")));
  std::byte* dst = nullptr;
  switch (info.dtype) {
    case DType::kUInt8:
      g.values8.resize(static_cast<size_t>(n));
      dst = reinterpret_cast<std::byte*>(g.values8.data());
      break;
    case DType::kUInt16:
      g.values16.resize(static_cast<size_t>(n));
      dst = reinterpret_cast<std::byte*>(g.values16.data());
      break;
    case DType::kFloat32:
      g.values.resize(static_cast<size_t>(n));
      dst = reinterpret_cast<std::byte*>(g.values.data());
      break;
  }
  // Readers give native byte order, the layout of the vectors: each slab straight in.
  const int64_t slice = g.dims.nx * g.dims.ny;
  const int64_t slab =
      std::clamp<int64_t>((int64_t{32} << 20) / std::max<int64_t>(1, slice * bytes), 1,
                          std::max<int64_t>(1, g.dims.nz));
  for (int64_t z0 = 0; z0 < g.dims.nz; z0 += slab) {
    const int64_t count = std::min(slab, g.dims.nz - z0);
    SM_RETURN_IF_ERROR(
        source.ReadSlices(z0, count,
                          std::span<std::byte>(dst + z0 * slice * bytes,
                                               static_cast<size_t>(count * slice * bytes))));
    SM_RETURN_IF_ERROR(progress.Update(double(z0 + count) / g.dims.nz));
  }
  return g;
}

namespace {

constexpr int kBins = 1024;

// The histogram of the finite values.
struct Histogram {
  double lo = 0, width = 1;
  std::vector<double> raw;
  double Value(int bin) const { return lo + (bin + 0.5) * width; }
  // Smoothed by a Gaussian of `sigma` bins (a peak of integer levels spread over several
  // bins, or ragged with noise, stays one peak).
  std::vector<double> Smoothed(double sigma) const {
    const int r = std::max(1, static_cast<int>(std::ceil(3 * sigma)));
    std::vector<double> k(2 * r + 1);
    for (int i = -r; i <= r; ++i) k[i + r] = std::exp(-0.5 * i * i / (sigma * sigma));
    std::vector<double> out(raw.size(), 0.0);
    for (int b = 0; b < static_cast<int>(raw.size()); ++b) {
      double s = 0, w = 0;
      for (int d = -r; d <= r; ++d) {
        if (b + d < 0 || b + d >= static_cast<int>(raw.size())) continue;
        s += k[d + r] * raw[b + d];
        w += k[d + r];
      }
      out[b] = s / w;
    }
    return out;
  }
};

// The volume's levels with how many voxels hold each: for 8- and 16-bit scans a count per
// integer level (so that the passes below cost nothing at any size), for floats each voxel.
struct LevelCounts {
  std::vector<std::pair<float, double>> counted;  // (level, voxels), levels with voxels
  const std::vector<float>* each = nullptr;       // float volumes: every voxel once

  explicit LevelCounts(const GreyVolume& grey) {
    if (grey.values8.empty() && grey.values16.empty()) {
      each = &grey.values;
      return;
    }
    std::vector<double> n(grey.values8.empty() ? 65536 : 256, 0.0);
    for (uint8_t v : grey.values8) ++n[v];
    for (uint16_t v : grey.values16) ++n[v];
    for (size_t v = 0; v < n.size(); ++v) {
      if (n[v] > 0) counted.emplace_back(static_cast<float>(v), n[v]);
    }
  }
  // Calls f(level, voxels) for every level.
  template <class F>
  void ForEach(F&& f) const {
    if (each) {
      for (float v : *each) f(v, 1.0);
    } else {
      for (const auto& [v, n] : counted) f(v, n);
    }
  }
};

Histogram MakeHistogram(const LevelCounts& levels, double lo, double hi) {
  Histogram h;
  h.lo = lo;
  h.width = (hi - lo) / kBins;
  h.raw.assign(kBins, 0.0);
  levels.ForEach([&](float v, double n) {
    if (!std::isfinite(v)) return;
    h.raw[std::clamp(static_cast<int>((v - lo) / h.width), 0, kBins - 1)] += n;
  });
  return h;
}

}  // namespace

absl::StatusOr<GreyLevels> MeasureGreyLevels(const GreyVolume& grey,
                                             std::optional<double> given_void,
                                             std::optional<double> given_rock,
                                             const std::string& path) {
  double lo = std::numeric_limits<double>::max(), hi = std::numeric_limits<double>::lowest();
  std::set<float> distinct;
  bool integral = true;
  const LevelCounts levels(grey);
  levels.ForEach([&](float v, double) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, double(v));
    hi = std::max(hi, double(v));
    if (distinct.size() <= 16) distinct.insert(v);
    integral = integral && v == std::floor(v);
  });
  if (!(lo < hi)) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": input.grey needs contrast, and every voxel is ",
                     lo <= hi ? absl::StrCat(lo) : std::string("not a number")));
  }
  if (integral && distinct.size() <= 16) {
    std::vector<std::string> v;
    for (float x : distinct) v.push_back(absl::StrCat(x));
    return absl::InvalidArgumentError(absl::StrCat(
        path, ": input.grey reads a scan's grey levels, and this volume holds only ",
        distinct.size(), " values (", absl::StrJoin(v, ", "),
        "): a segmented or label volume; select its sheet phase with input.labels instead"));
  }
  if (given_void && given_rock && !(*given_void < *given_rock)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "grey.levels = [", *given_void, ", ", *given_rock,
        "]: the void's level must be below the rock's (sheets are darker than the rock)"));
  }
  const Histogram h = MakeHistogram(levels, lo, hi);
  GreyLevels out;
  // The rock: the highest peak, found on a coarse smoothing, then placed on one at a
  // quarter of the noise it shows.
  auto half_width_right = [&](const std::vector<double>& c, int peak) {
    int right = peak;
    while (right + 1 < kBins && c[right + 1] > 0.5 * c[peak]) ++right;
    return std::max(0.5, double(right - peak) + 0.5);  // bins
  };
  const double coarse = kBins / 200.0;
  std::vector<double> counts = h.Smoothed(coarse);
  int peak = static_cast<int>(std::max_element(counts.begin(), counts.end()) - counts.begin());
  // The noise from the brighter side's half width at half maximum (the darker one carries
  // the sheets' partial voxels), less the smoothing's own.
  auto noise_of = [&](double hw_bins, double smoothing_bins) {
    const double s = hw_bins / std::sqrt(2 * std::log(2.0));
    return std::sqrt(std::max(0.25, s * s - smoothing_bins * smoothing_bins)) * h.width;
  };
  out.noise = noise_of(half_width_right(counts, peak), coarse);
  const double fine = std::max(1.0, 0.25 * out.noise / h.width);
  counts = h.Smoothed(fine);
  peak = static_cast<int>(std::max_element(counts.begin(), counts.end()) - counts.begin());
  out.noise = noise_of(half_width_right(counts, peak), fine);
  // The level: the mean of the voxels within one noise width of the peak, the window moved
  // onto that mean until it settles (a mode to a fraction of the noise).
  double rock = h.Value(peak);
  for (int pass = 0; pass < 8; ++pass) {
    double sum = 0, n = 0;
    levels.ForEach([&](float v, double count) {
      if (std::isfinite(v) && std::abs(v - rock) <= out.noise) {
        sum += count * v;
        n += count;
      }
    });
    if (n == 0) break;
    const double next = sum / n;
    const bool settled = std::abs(next - rock) < 1e-3 * out.noise;
    rock = next;
    if (settled) break;
  }
  out.rock = given_rock ? *given_rock : rock;
  out.rock_measured = !given_rock;
  if (given_void) {
    out.void_level = *given_void;
  } else {
    // The void: the highest peak of the histogram (smoothed at half the noise) darker than
    // the rock by three times the noise that is a peak of its own — the histogram falls
    // below half its height between it and the rock, so it is neither the rock's tail nor
    // the sheets' partial voxels leaning on it — holding a thousandth of the voxels within
    // two noise widths.
    const std::vector<double> smooth = h.Smoothed(std::max(1.0, 0.5 * out.noise / h.width));
    const int edge =
        std::clamp(static_cast<int>((out.rock - 3 * out.noise - h.lo) / h.width), 0, kBins - 1);
    // From the rock down: the lowest the histogram has been since the rock, and the
    // highest local maximum standing twice as high as that.
    int best = -1;
    double lowest = smooth[edge];
    for (int b = edge - 1; b >= 1; --b) {
      lowest = std::min(lowest, smooth[b]);
      const bool local_max = smooth[b] >= smooth[b - 1] && smooth[b] >= smooth[b + 1];
      if (local_max && smooth[b] > 2 * lowest && (best < 0 || smooth[b] > smooth[best])) {
        best = b;
      }
    }
    double total = 0, mass = 0;
    for (double c : h.raw) total += c;
    const int reach = std::max(1, static_cast<int>(2 * out.noise / h.width));
    if (best >= 0) {
      for (int b = std::max(0, best - reach); b <= std::min(kBins - 1, best + reach); ++b) {
        mass += h.raw[b];
      }
    }
    if (best >= 0 && mass >= 1e-3 * total) {
      out.void_level = h.Value(best);
      out.void_measured = true;
    } else {
      out.void_level = lo;
      out.problem = absl::StrCat("no void phase in the histogram (no peak darker than the rock at ",
                                 out.rock, " by three times the noise, ", out.noise,
                                 "), and none given (grey.levels = [VOID, ROCK])");
    }
  }
  if (out.problem.empty() && !(out.contrast() > 3 * out.noise)) {
    out.problem =
        absl::StrCat("the contrast between the rock (", out.rock, ") and the void (",
                     out.void_level, ") is under three times the noise (", out.noise, ")");
  }
  return out;
}

}  // namespace sheetmesh
