#include "worker/pipeline/voxel/voxel_set.h"

#include <algorithm>

#include "common/assert.h"

namespace sheetmesh {

VoxelSet::VoxelSet(const Dims& dims) : dims_(dims), row_begin_(dims.num_rows() + 1, 0) {
  run_first_.push_back(0);
}

int64_t VoxelSet::Find(int64_t x, int64_t y, int64_t z) const {
  if (!dims_.Contains(x, y, z)) return -1;
  const int64_t r = RowId(y, z);
  int64_t lo = row_begin_[r];
  int64_t hi = row_begin_[r + 1];
  // Rows hold a handful of runs; a linear scan beats binary search until they get long.
  if (hi - lo <= 8) {
    for (int64_t i = lo; i < hi; ++i) {
      if (x < runs_[i].x0) return -1;
      if (x < runs_[i].x1) return static_cast<int64_t>(run_first_[i] + (x - runs_[i].x0));
    }
    return -1;
  }
  while (lo < hi) {
    const int64_t mid = (lo + hi) / 2;
    if (runs_[mid].x1 <= x) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  if (lo < row_begin_[r + 1] && runs_[lo].x0 <= x) {
    return static_cast<int64_t>(run_first_[lo] + (x - runs_[lo].x0));
  }
  return -1;
}

Index3 VoxelSet::CoordOf(uint64_t index) const {
  SM_ASSERT(index < size());
  // The run holding `index`: last run whose first index is <= index.
  const auto it = std::upper_bound(run_first_.begin(), run_first_.end() - 1, index);
  const int64_t run = (it - run_first_.begin()) - 1;
  // The row holding that run: last row whose begin is <= run with a non-empty range.
  const auto rit = std::upper_bound(row_begin_.begin(), row_begin_.end(), run);
  const int64_t row = (rit - row_begin_.begin()) - 1;
  Index3 c;
  c.x = runs_[run].x0 + static_cast<int32_t>(index - run_first_[run]);
  c.y = static_cast<int32_t>(row % dims_.ny);
  c.z = static_cast<int32_t>(row / dims_.ny);
  return c;
}

void VoxelSet::Bounds(Index3* lo, Index3* hi) const {
  *lo = {INT32_MAX, INT32_MAX, INT32_MAX};
  *hi = {INT32_MIN, INT32_MIN, INT32_MIN};
  ForEachRun([&](int32_t y, int32_t z, const Run& run, uint64_t) {
    lo->x = std::min(lo->x, run.x0);
    hi->x = std::max(hi->x, run.x1 - 1);
    lo->y = std::min(lo->y, y);
    hi->y = std::max(hi->y, y);
    lo->z = std::min(lo->z, z);
    hi->z = std::max(hi->z, z);
  });
}

std::vector<Index3> VoxelSet::ToIndices() const {
  std::vector<Index3> out;
  out.reserve(size());
  ForEachVoxel([&](uint64_t, int32_t x, int32_t y, int32_t z) { out.push_back({x, y, z}); });
  return out;
}

VoxelSet VoxelSet::FromIndices(const Dims& dims, std::vector<Index3> indices) {
  std::sort(indices.begin(), indices.end(), [](const Index3& a, const Index3& b) {
    if (a.z != b.z) return a.z < b.z;
    if (a.y != b.y) return a.y < b.y;
    return a.x < b.x;
  });
  Builder builder(dims);
  for (const Index3& i : indices) {
    if (dims.Contains(i.x, i.y, i.z)) builder.AddVoxel(i.x, i.y, i.z);
  }
  return std::move(builder).Build();
}

VoxelSet VoxelSet::Filter(std::span<const uint8_t> keep) const {
  SM_ASSERT(keep.size() == size());
  Builder builder(dims_);
  ForEachRun([&](int32_t y, int32_t z, const Run& run, uint64_t first) {
    int32_t start = -1;
    for (int32_t x = run.x0; x < run.x1; ++x) {
      const bool k = keep[first + (x - run.x0)] != 0;
      if (k && start < 0) start = x;
      if (!k && start >= 0) {
        builder.AddRun(y, z, start, x);
        start = -1;
      }
    }
    if (start >= 0) builder.AddRun(y, z, start, run.x1);
  });
  return std::move(builder).Build();
}

VoxelSet VoxelSet::Crop(const Index3& lo, const Dims& dims) const {
  Builder builder(dims);
  const int64_t z0 = std::max<int64_t>(lo.z, 0), z1 = std::min<int64_t>(lo.z + dims.nz, dims_.nz);
  const int64_t y0 = std::max<int64_t>(lo.y, 0), y1 = std::min<int64_t>(lo.y + dims.ny, dims_.ny);
  for (int64_t z = z0; z < z1; ++z) {
    for (int64_t y = y0; y < y1; ++y) {
      for (const Run& run : RowRuns(y, z)) {
        const int64_t x0 = std::max<int64_t>(run.x0, lo.x);
        const int64_t x1 = std::min<int64_t>(run.x1, lo.x + dims.nx);
        if (x0 < x1) builder.AddRun(y - lo.y, z - lo.z, x0 - lo.x, x1 - lo.x);
      }
    }
  }
  return std::move(builder).Build();
}

uint64_t VoxelSet::MemoryBytes() const {
  return row_begin_.capacity() * sizeof(int64_t) + runs_.capacity() * sizeof(Run) +
         run_first_.capacity() * sizeof(uint64_t);
}

VoxelSet::Builder::Builder(const Dims& dims) {
  set_.dims_ = dims;
  set_.row_begin_.assign(dims.num_rows() + 1, 0);
  set_.run_first_.push_back(0);
}

void VoxelSet::Builder::CloseRowsUpTo(int64_t row) {
  // Rows before `row` are complete: their end is the current run count.
  while (current_row_ < row) {
    ++current_row_;
    set_.row_begin_[current_row_] = static_cast<int64_t>(set_.runs_.size());
  }
}

void VoxelSet::Builder::AddRun(int64_t y, int64_t z, int64_t x0, int64_t x1) {
  const Dims& d = set_.dims_;
  if (y < 0 || z < 0 || y >= d.ny || z >= d.nz) return;
  x0 = std::max<int64_t>(x0, 0);
  x1 = std::min<int64_t>(x1, d.nx);
  if (x0 >= x1) return;
  const int64_t row = z * d.ny + y;
  SM_ASSERT(row >= current_row_);
  CloseRowsUpTo(row);
  std::vector<Run>& runs = set_.runs_;
  const bool same_row = static_cast<int64_t>(runs.size()) > set_.row_begin_[row];
  if (same_row && runs.back().x1 >= x0) {
    SM_ASSERT(x0 >= runs.back().x0);
    const int32_t grow =
        static_cast<int32_t>(std::max<int64_t>(x1, runs.back().x1)) - runs.back().x1;
    runs.back().x1 += grow;
    set_.run_first_.back() += grow;
    return;
  }
  runs.push_back({static_cast<int32_t>(x0), static_cast<int32_t>(x1)});
  set_.run_first_.push_back(set_.run_first_.back() + (x1 - x0));
}

VoxelSet VoxelSet::Builder::Build() && {
  CloseRowsUpTo(set_.dims_.num_rows());
  set_.runs_.shrink_to_fit();
  set_.run_first_.shrink_to_fit();
  return std::move(set_);
}

void UnionRuns(std::span<const Run> a, std::span<const Run> b, std::vector<Run>* out) {
  size_t i = 0, j = 0;
  const size_t start = out->size();
  auto push = [&](const Run& r) {
    if (out->size() > start && out->back().x1 >= r.x0) {
      out->back().x1 = std::max(out->back().x1, r.x1);
    } else {
      out->push_back(r);
    }
  };
  while (i < a.size() || j < b.size()) {
    if (j >= b.size() || (i < a.size() && a[i].x0 <= b[j].x0)) {
      push(a[i++]);
    } else {
      push(b[j++]);
    }
  }
}

void IntersectRuns(std::span<const Run> a, std::span<const Run> b, std::vector<Run>* out) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const int32_t lo = std::max(a[i].x0, b[j].x0);
    const int32_t hi = std::min(a[i].x1, b[j].x1);
    if (lo < hi) out->push_back({lo, hi});
    if (a[i].x1 < b[j].x1) {
      ++i;
    } else {
      ++j;
    }
  }
}

namespace {

void SubtractRuns(std::span<const Run> a, std::span<const Run> b, std::vector<Run>* out) {
  size_t j = 0;
  for (const Run& r : a) {
    int32_t x = r.x0;
    while (j < b.size() && b[j].x1 <= x) ++j;
    size_t k = j;
    while (x < r.x1) {
      if (k >= b.size() || b[k].x0 >= r.x1) {
        out->push_back({x, r.x1});
        break;
      }
      if (b[k].x0 > x) out->push_back({x, b[k].x0});
      x = std::max(x, b[k].x1);
      ++k;
    }
  }
}

template <class Op>
VoxelSet RowWise(const VoxelSet& a, const VoxelSet& b, Op op) {
  SM_ASSERT(a.dims() == b.dims());
  VoxelSet::Builder builder(a.dims());
  std::vector<Run> row;
  for (int64_t z = 0; z < a.dims().nz; ++z) {
    for (int64_t y = 0; y < a.dims().ny; ++y) {
      row.clear();
      op(a.RowRuns(y, z), b.RowRuns(y, z), &row);
      for (const Run& r : row) builder.AddRun(y, z, r.x0, r.x1);
    }
  }
  return std::move(builder).Build();
}

}  // namespace

VoxelSet Union(const VoxelSet& a, const VoxelSet& b) { return RowWise(a, b, UnionRuns); }
VoxelSet Intersection(const VoxelSet& a, const VoxelSet& b) { return RowWise(a, b, IntersectRuns); }
VoxelSet Difference(const VoxelSet& a, const VoxelSet& b) { return RowWise(a, b, SubtractRuns); }

}  // namespace sheetmesh
