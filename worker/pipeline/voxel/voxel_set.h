// VoxelSet: a sparse set of voxels in a box, stored as sorted x-runs per (y, z) row.
// Memory follows the number of runs (about the sheet voxels divided by their thickness
// along x), not the box. Voxels have a dense index 0..size()-1 in (z, y, x) order, so
// per-voxel attributes live in plain arrays aligned with that order.
#ifndef SHEETMESH_WORKER_PIPELINE_VOXEL_VOXEL_SET_H_
#define SHEETMESH_WORKER_PIPELINE_VOXEL_VOXEL_SET_H_

#include <cstdint>
#include <span>
#include <vector>

#include "common/types.h"

namespace sheetmesh {

// Voxels x in [x0, x1) of one row.
struct Run {
  int32_t x0 = 0;
  int32_t x1 = 0;
  int32_t length() const { return x1 - x0; }
  friend bool operator==(const Run&, const Run&) = default;
};

// Immutable once built; copyable. Thread-compatible: const methods may be called
// concurrently.
class VoxelSet {
 public:
  class Builder;

  VoxelSet() = default;
  // The empty set in a box of `dims`.
  explicit VoxelSet(const Dims& dims);

  const Dims& dims() const { return dims_; }
  // Number of voxels.
  uint64_t size() const { return run_first_.empty() ? 0 : run_first_.back(); }
  bool empty() const { return size() == 0; }
  int64_t num_runs() const { return static_cast<int64_t>(runs_.size()); }

  int64_t RowId(int64_t y, int64_t z) const { return z * dims_.ny + y; }
  // The runs of row (y, z), in increasing x. REQUIRES: 0 <= y < ny, 0 <= z < nz.
  std::span<const Run> RowRuns(int64_t y, int64_t z) const {
    const int64_t r = RowId(y, z);
    return {runs_.data() + row_begin_[r], runs_.data() + row_begin_[r + 1]};
  }
  // Index of the first run of row `row`; runs of the row are [RowBegin(row), RowBegin(row+1)).
  int64_t RowBegin(int64_t row) const { return row_begin_[row]; }
  const Run& run(int64_t i) const { return runs_[i]; }
  // Voxel index of the first voxel of run `i`.
  uint64_t RunFirstIndex(int64_t i) const { return run_first_[i]; }

  // Voxel index of (x, y, z), or -1 if the voxel is not in the set or outside the box.
  int64_t Find(int64_t x, int64_t y, int64_t z) const;
  bool Contains(int64_t x, int64_t y, int64_t z) const { return Find(x, y, z) >= 0; }
  // Coordinates of voxel `index`. O(log runs). REQUIRES: index < size().
  Index3 CoordOf(uint64_t index) const;

  // Calls f(y, z, run, first_index) for every run in (z, y, x) order.
  template <class F>
  void ForEachRun(F&& f) const {
    for (int64_t z = 0; z < dims_.nz; ++z) {
      for (int64_t y = 0; y < dims_.ny; ++y) {
        const int64_t r = RowId(y, z);
        for (int64_t i = row_begin_[r]; i < row_begin_[r + 1]; ++i) {
          f(static_cast<int32_t>(y), static_cast<int32_t>(z), runs_[i], run_first_[i]);
        }
      }
    }
  }
  // Calls f(index, x, y, z) for every voxel in index order.
  template <class F>
  void ForEachVoxel(F&& f) const {
    ForEachRun([&](int32_t y, int32_t z, const Run& run, uint64_t first) {
      for (int32_t x = run.x0; x < run.x1; ++x) f(first + (x - run.x0), x, y, z);
    });
  }

  // The bounding box of the set as [lo, hi] inclusive; lo > hi when empty.
  void Bounds(Index3* lo, Index3* hi) const;

  // All voxel coordinates in index order (for tests and small sets).
  std::vector<Index3> ToIndices() const;
  // The set of `indices` in `dims` (duplicates allowed; outside the box ignored).
  static VoxelSet FromIndices(const Dims& dims, std::vector<Index3> indices);
  // The voxels whose flag is set; `keep` is aligned with this set's voxel order.
  VoxelSet Filter(std::span<const uint8_t> keep) const;

  // The voxels in the box of `dims` whose corner is `lo`, as a set of that box (voxel lo is
  // its (0, 0, 0)); the box may reach outside this one.
  VoxelSet Crop(const Index3& lo, const Dims& dims) const;

  // Approximate heap bytes held.
  uint64_t MemoryBytes() const;

  friend bool operator==(const VoxelSet& a, const VoxelSet& b) {
    return a.dims_ == b.dims_ && a.row_begin_ == b.row_begin_ && a.runs_ == b.runs_;
  }

 private:
  Dims dims_;
  std::vector<int64_t> row_begin_;   // size num_rows + 1, index into runs_
  std::vector<Run> runs_;            // sorted, disjoint, non-adjacent within a row
  std::vector<uint64_t> run_first_;  // size num_runs + 1: voxel index of each run's start
};

// Builds a VoxelSet row by row. Not thread-safe.
class VoxelSet::Builder {
 public:
  explicit Builder(const Dims& dims);

  // Adds voxels [x0, x1) of row (y, z), clipped to the box. Rows must come in (z, y)
  // order; within a row, runs must come in non-decreasing x0. Overlapping or touching runs
  // merge. REQUIRES: the order above.
  void AddRun(int64_t y, int64_t z, int64_t x0, int64_t x1);
  void AddVoxel(int64_t x, int64_t y, int64_t z) { AddRun(y, z, x, x + 1); }

  VoxelSet Build() &&;

 private:
  void CloseRowsUpTo(int64_t row);

  VoxelSet set_;
  int64_t current_row_ = 0;
};

// Set algebra on sets of the same dims. REQUIRES: equal dims.
VoxelSet Union(const VoxelSet& a, const VoxelSet& b);
VoxelSet Intersection(const VoxelSet& a, const VoxelSet& b);
VoxelSet Difference(const VoxelSet& a, const VoxelSet& b);

// Appends to `out` the union of the sorted run lists `a` and `b` (merging touching runs).
void UnionRuns(std::span<const Run> a, std::span<const Run> b, std::vector<Run>* out);
// Appends to `out` the intersection of sorted run lists `a` and `b`.
void IntersectRuns(std::span<const Run> a, std::span<const Run> b, std::vector<Run>* out);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOXEL_VOXEL_SET_H_
