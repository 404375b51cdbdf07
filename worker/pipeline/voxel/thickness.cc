#include "worker/pipeline/voxel/thickness.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <climits>

#include "common/status_macros.h"

namespace sheetmesh {
namespace {

constexpr uint32_t kSaturate = 65535;
constexpr int32_t kNever = INT32_MIN;

// Per-column state of a sweep: where the column last held a voxel and how long its run was.
struct ColumnState {
  std::vector<int32_t> last;
  std::vector<uint32_t> count;
  explicit ColumnState(size_t n) : last(n, kNever), count(n, 0) {}
  void Reset() { std::fill(last.begin(), last.end(), kNever); }
};

// Counts, for each voxel of a row, the voxels of its column run up to and including it
// seen from the sweep's direction. `pos` is the row's position along the axis and `step`
// +1 (forward) or -1 (backward). The sum of both directions minus one is the run.
template <class Visit>
void CountRow(const VoxelSet& set, int64_t row, int32_t pos, int32_t step, int64_t col0,
              ColumnState* state, Visit visit) {
  for (int64_t i = set.RowBegin(row); i < set.RowBegin(row + 1); ++i) {
    const Run& run = set.run(i);
    const uint64_t first = set.RunFirstIndex(i);
    for (int32_t x = run.x0; x < run.x1; ++x) {
      const int64_t col = col0 + x;
      const uint32_t c =
          state->last[col] == pos - step ? std::min(state->count[col] + 1, kSaturate) : 1;
      state->last[col] = pos;
      state->count[col] = c;
      visit(first + (x - run.x0), c);
    }
  }
}

// Runs along y: slices are independent, so they run in parallel.
void YRuns(const VoxelSet& set, std::vector<uint16_t>* partial, std::vector<uint16_t>* tau) {
  const Dims& d = set.dims();
  tbb::parallel_for(
      tbb::blocked_range<int64_t>(0, d.nz), [&](const tbb::blocked_range<int64_t>& r) {
        ColumnState state(static_cast<size_t>(d.nx));
        for (int64_t z = r.begin(); z < r.end(); ++z) {
          state.Reset();
          for (int64_t y = 0; y < d.ny; ++y) {
            CountRow(set, set.RowId(y, z), static_cast<int32_t>(y), 1, 0, &state,
                     [&](uint64_t i, uint32_t c) { (*partial)[i] = static_cast<uint16_t>(c); });
          }
          state.Reset();
          for (int64_t y = d.ny - 1; y >= 0; --y) {
            CountRow(set, set.RowId(y, z), static_cast<int32_t>(y), -1, 0, &state,
                     [&](uint64_t i, uint32_t c) {
                       const uint32_t run = std::min<uint32_t>((*partial)[i] + c - 1, kSaturate);
                       (*tau)[i] = static_cast<uint16_t>(std::min<uint32_t>((*tau)[i], run));
                     });
          }
        }
      });
}

// Runs along z: columns with different y are independent, so bands of y run in parallel.
void ZRuns(const VoxelSet& set, std::vector<uint16_t>* partial, std::vector<uint16_t>* tau) {
  const Dims& d = set.dims();
  tbb::parallel_for(
      tbb::blocked_range<int64_t>(0, d.ny, 16), [&](const tbb::blocked_range<int64_t>& r) {
        ColumnState state(static_cast<size_t>((r.end() - r.begin()) * d.nx));
        for (int64_t z = 0; z < d.nz; ++z) {
          for (int64_t y = r.begin(); y < r.end(); ++y) {
            CountRow(set, set.RowId(y, z), static_cast<int32_t>(z), 1, (y - r.begin()) * d.nx,
                     &state,
                     [&](uint64_t i, uint32_t c) { (*partial)[i] = static_cast<uint16_t>(c); });
          }
        }
        state.Reset();
        for (int64_t z = d.nz - 1; z >= 0; --z) {
          for (int64_t y = r.begin(); y < r.end(); ++y) {
            CountRow(set, set.RowId(y, z), static_cast<int32_t>(z), -1, (y - r.begin()) * d.nx,
                     &state, [&](uint64_t i, uint32_t c) {
                       const uint32_t run = std::min<uint32_t>((*partial)[i] + c - 1, kSaturate);
                       (*tau)[i] = static_cast<uint16_t>(std::min<uint32_t>((*tau)[i], run));
                     });
          }
        }
      });
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
  std::vector<uint16_t> partial(set.size());
  YRuns(set, &partial, &tau);
  SM_RETURN_IF_ERROR(progress.Update(0.6));
  ZRuns(set, &partial, &tau);
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
