#include "worker/pipeline/voxel/thickness.h"

#include <algorithm>

#include "worker/pipeline/core/status_macros.h"

namespace sheetmesh {
namespace {

constexpr uint32_t kSaturate = 65535;

// Visits voxels as (index, x, y, z) in increasing or decreasing index order.
template <class F>
void Sweep(const VoxelSet& set, bool forward, F&& f) {
  const Dims& d = set.dims();
  const int64_t rows = d.num_rows();
  for (int64_t rr = 0; rr < rows; ++rr) {
    const int64_t row = forward ? rr : rows - 1 - rr;
    const int32_t y = static_cast<int32_t>(row % d.ny);
    const int32_t z = static_cast<int32_t>(row / d.ny);
    const int64_t b = set.RowBegin(row), e = set.RowBegin(row + 1);
    for (int64_t ii = b; ii < e; ++ii) {
      const int64_t i = forward ? ii : e - 1 - (ii - b);
      const Run& run = set.run(i);
      const uint64_t first = set.RunFirstIndex(i);
      for (int32_t k = 0; k < run.length(); ++k) {
        const int32_t x = forward ? run.x0 + k : run.x1 - 1 - k;
        f(first + (x - run.x0), x, y, z);
      }
    }
  }
}

// Run lengths along y (axis 1) or z (axis 2): a forward sweep counts the voxels of the
// run up to each voxel, a backward sweep from the other end; their sum minus one is the
// whole run. `stamp` remembers, per column, which row last held a voxel.
void AxisRuns(const VoxelSet& set, int axis, std::vector<uint16_t>* tau) {
  const Dims& d = set.dims();
  const int64_t columns = axis == 1 ? d.nx : d.nx * d.ny;
  std::vector<int64_t> stamp(static_cast<size_t>(columns));
  std::vector<uint32_t> count(static_cast<size_t>(columns));
  std::vector<uint16_t> partial(set.size());
  for (int pass = 0; pass < 2; ++pass) {
    const bool forward = pass == 0;
    std::fill(stamp.begin(), stamp.end(), INT64_MIN);
    Sweep(set, forward, [&](uint64_t i, int32_t x, int32_t y, int32_t z) {
      // Position along the axis and column. For y the position is global over slices with
      // a gap of one between them, so that runs never continue from one slice to the next
      // and no reset is needed.
      const int64_t pos = axis == 1 ? int64_t{z} * (d.ny + 1) + y : z;
      const int64_t col = axis == 1 ? x : int64_t{y} * d.nx + x;
      const int64_t prev = forward ? pos - 1 : pos + 1;
      const uint32_t c = stamp[col] == prev ? std::min(count[col] + 1, kSaturate) : 1;
      stamp[col] = pos;
      count[col] = c;
      if (forward) {
        partial[i] = static_cast<uint16_t>(c);
      } else {
        const uint32_t run = std::min<uint32_t>(partial[i] + c - 1, kSaturate);
        (*tau)[i] = static_cast<uint16_t>(std::min<uint32_t>((*tau)[i], run));
      }
    });
  }
}

}  // namespace

absl::StatusOr<std::vector<uint16_t>> ComputeThickness(const VoxelSet& set,
                                                       const Progress& progress) {
  std::vector<uint16_t> tau(set.size());
  set.ForEachRun([&](int32_t, int32_t, const Run& run, uint64_t first) {
    const uint16_t len = static_cast<uint16_t>(std::min<uint32_t>(run.length(), kSaturate));
    std::fill(tau.begin() + first, tau.begin() + first + run.length(), len);
  });
  SM_RETURN_IF_ERROR(progress.Update(0.2));
  AxisRuns(set, 1, &tau);
  SM_RETURN_IF_ERROR(progress.Update(0.6));
  AxisRuns(set, 2, &tau);
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return tau;
}

ThicknessStats SummarizeThickness(std::span<const uint16_t> thickness) {
  ThicknessStats s;
  if (thickness.empty()) return s;
  s.histogram.assign(kSaturate + 1, 0);
  uint64_t sum = 0;
  for (uint16_t t : thickness) {
    ++s.histogram[t];
    sum += t;
  }
  s.mean = static_cast<double>(sum) / thickness.size();
  uint32_t last = 0;
  for (uint32_t t = 0; t <= kSaturate; ++t) {
    if (s.histogram[t] == 0) continue;
    if (s.min == 0) s.min = t;
    last = t;
  }
  s.max = last;
  s.histogram.resize(last + 1);
  // Median: the middle value (lower middle for an even count).
  const uint64_t half = (thickness.size() + 1) / 2;
  uint64_t seen = 0;
  for (uint32_t t = 0; t <= last; ++t) {
    seen += s.histogram[t];
    if (seen >= half) {
      s.median = t;
      break;
    }
  }
  return s;
}

}  // namespace sheetmesh
