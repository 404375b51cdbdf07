#include "worker/pipeline/voxel/threshold.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "common/status_macros.h"

namespace sheetmesh {
namespace {

// Calls visit(values, count) for each slab of the volume, as `T`.
template <class T, class F>
absl::Status ForEachSlab(VolumeSource& source, const Progress& progress, F visit) {
  const Dims& d = source.info().dims;
  const int64_t slice = d.nx * d.ny;
  const int64_t slab = std::clamp<int64_t>(
      (int64_t{32} << 20) / std::max<int64_t>(1, slice * int64_t{sizeof(T)}), 1, d.nz);
  std::vector<T> buffer(static_cast<size_t>(slab * slice));
  for (int64_t z0 = 0; z0 < d.nz; z0 += slab) {
    const int64_t count = std::min(slab, d.nz - z0);
    std::span<std::byte> bytes(reinterpret_cast<std::byte*>(buffer.data()),
                               static_cast<size_t>(count * slice) * sizeof(T));
    SM_RETURN_IF_ERROR(source.ReadSlices(z0, count, bytes));
    visit(buffer.data(), count * slice);
    SM_RETURN_IF_ERROR(progress.Update(double(z0 + count) / d.nz));
  }
  return absl::OkStatus();
}

template <class T>
absl::StatusOr<double> OtsuOfIntegers(VolumeSource& source, const Progress& progress) {
  std::vector<uint64_t> counts(size_t{1} << (8 * sizeof(T)), 0);
  SM_RETURN_IF_ERROR(ForEachSlab<T>(source, progress, [&](const T* v, int64_t n) {
    for (int64_t i = 0; i < n; ++i) ++counts[v[i]];
  }));
  // Bins of width 1 starting at -0.5: the threshold is the upper edge +0.5 of the last
  // value of the low class, so "below" keeps exactly the values up to it.
  return OtsuOfHistogram(counts, -0.5, 1.0);
}

absl::StatusOr<double> OtsuOfFloats(VolumeSource& source, const Progress& progress) {
  float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
  SM_RETURN_IF_ERROR(
      ForEachSlab<float>(source, progress.Sub(0, 0.5), [&](const float* v, int64_t n) {
        for (int64_t i = 0; i < n; ++i) {
          if (std::isnan(v[i])) continue;
          lo = std::min(lo, v[i]);
          hi = std::max(hi, v[i]);
        }
      }));
  if (!(lo < hi)) return static_cast<double>(lo);
  constexpr int kBins = 4096;
  const double width = (double(hi) - lo) / kBins;
  std::vector<uint64_t> counts(kBins, 0);
  SM_RETURN_IF_ERROR(
      ForEachSlab<float>(source, progress.Sub(0.5, 1), [&](const float* v, int64_t n) {
        for (int64_t i = 0; i < n; ++i) {
          if (std::isnan(v[i])) continue;
          const int b = std::min(kBins - 1, static_cast<int>((v[i] - lo) / width));
          ++counts[b];
        }
      }));
  return OtsuOfHistogram(counts, lo, width);
}

}  // namespace

double OtsuOfHistogram(std::span<const uint64_t> counts, double lo, double bin_width) {
  double total = 0, sum = 0;
  for (size_t i = 0; i < counts.size(); ++i) {
    total += double(counts[i]);
    sum += double(i) * double(counts[i]);
  }
  double best = -1, w0 = 0, sum0 = 0;
  size_t split = 0, best_last = 0;
  for (size_t i = 0; i + 1 < counts.size(); ++i) {
    w0 += double(counts[i]);
    sum0 += double(i) * double(counts[i]);
    const double w1 = total - w0;
    if (w0 == 0 || w1 == 0) continue;
    const double m0 = sum0 / w0, m1 = (sum - sum0) / w1;
    const double between = w0 * w1 * (m0 - m1) * (m0 - m1);
    // Ties (empty bins between the classes) take the middle of the flat stretch.
    if (between > best * (1 + 1e-12)) {
      best = between;
      split = best_last = i;
    } else if (between >= best * (1 - 1e-12)) {
      best_last = i;
    }
  }
  if (best < 0) return lo;
  const size_t mid = (split + best_last) / 2;
  return lo + double(mid + 1) * bin_width;
}

absl::StatusOr<double> OtsuThreshold(VolumeSource& source, const Progress& progress) {
  switch (source.info().dtype) {
    case DType::kUInt8:
      return OtsuOfIntegers<uint8_t>(source, progress);
    case DType::kUInt16:
      return OtsuOfIntegers<uint16_t>(source, progress);
    case DType::kFloat32:
      return OtsuOfFloats(source, progress);
  }
  return absl::InternalError("unknown dtype");
}

absl::StatusOr<ThresholdSpec> ParseThreshold(const std::string& text) {
  ThresholdSpec s;
  const std::string t = absl::AsciiStrToLower(absl::StripAsciiWhitespace(text));
  if (t == "otsu") {
    s.otsu = true;
    return s;
  }
  if (absl::SimpleAtod(t, &s.value) && std::isfinite(s.value)) return s;
  return absl::InvalidArgumentError(
      absl::StrCat("input.threshold = '", text, "' must be 'otsu' or a number (--threshold=otsu)"));
}

PhaseSelection SideOfThreshold(double t, bool above) {
  if (above) return PhaseSelection::Window(t, std::numeric_limits<double>::max());
  return PhaseSelection::Window(std::numeric_limits<double>::lowest(),
                                std::nextafter(t, std::numeric_limits<double>::lowest()));
}

}  // namespace sheetmesh
