#include "worker/pipeline/voxel/components.h"

#include <algorithm>
#include <numeric>

#include "absl/strings/str_cat.h"
#include "common/status_macros.h"

namespace sheetmesh {
namespace {

class UnionFind {
 public:
  explicit UnionFind(size_t n) : parent_(n) { std::iota(parent_.begin(), parent_.end(), 0u); }
  uint32_t Find(uint32_t a) {
    while (parent_[a] != a) {
      parent_[a] = parent_[parent_[a]];
      a = parent_[a];
    }
    return a;
  }
  void Union(uint32_t a, uint32_t b) {
    a = Find(a);
    b = Find(b);
    // The smaller id wins so that roots are the earliest runs.
    if (a < b) {
      parent_[b] = a;
    } else if (b < a) {
      parent_[a] = b;
    }
  }

 private:
  std::vector<uint32_t> parent_;
};

// Unions runs of row `a` (indices [ab, ae)) with those of row `b` that touch them when
// runs are widened by `widen` voxels in x.
void LinkRows(const VoxelSet& set, int64_t ab, int64_t ae, int64_t bb, int64_t be, int widen,
              UnionFind* uf) {
  int64_t j = bb;
  for (int64_t i = ab; i < ae; ++i) {
    const Run& r = set.run(i);
    while (j < be && set.run(j).x1 + widen <= r.x0) ++j;
    for (int64_t k = j; k < be && set.run(k).x0 < r.x1 + widen; ++k) {
      uf->Union(static_cast<uint32_t>(i), static_cast<uint32_t>(k));
    }
  }
}

}  // namespace

absl::StatusOr<Connectivity> ParseConnectivity(int n) {
  if (n == 6) return Connectivity::k6;
  if (n == 18) return Connectivity::k18;
  if (n == 26) return Connectivity::k26;
  return absl::InvalidArgumentError(
      absl::StrCat("connectivity ", n, " is not supported; use 6, 18 or 26"));
}

std::vector<uint32_t> Components::VoxelLabels(const VoxelSet& set) const {
  std::vector<uint32_t> out(set.size());
  for (int64_t i = 0; i < set.num_runs(); ++i) {
    const uint64_t first = set.RunFirstIndex(i);
    std::fill(out.begin() + first, out.begin() + first + set.run(i).length(), run_label[i]);
  }
  return out;
}

absl::StatusOr<Components> LabelComponents(const VoxelSet& set, Connectivity connectivity,
                                           const Progress& progress) {
  if (set.num_runs() >= static_cast<int64_t>(UINT32_MAX)) {
    return absl::ResourceExhaustedError(
        absl::StrCat(set.num_runs(), " runs exceed the component labeller's 2^32 limit"));
  }
  const Dims& d = set.dims();
  UnionFind uf(static_cast<size_t>(set.num_runs()));
  // Neighbour rows already visited, as (dy, dz, x widening) per connectivity.
  struct Offset {
    int dy, dz, widen;
  };
  std::vector<Offset> offsets;
  switch (connectivity) {
    case Connectivity::k6:
      offsets = {{-1, 0, 0}, {0, -1, 0}};
      break;
    case Connectivity::k18:
      offsets = {{-1, 0, 1}, {0, -1, 1}, {-1, -1, 0}, {1, -1, 0}};
      break;
    case Connectivity::k26:
      offsets = {{-1, 0, 1}, {0, -1, 1}, {-1, -1, 1}, {1, -1, 1}};
      break;
  }
  for (int64_t z = 0; z < d.nz; ++z) {
    for (int64_t y = 0; y < d.ny; ++y) {
      const int64_t row = z * d.ny + y;
      const int64_t ab = set.RowBegin(row), ae = set.RowBegin(row + 1);
      if (ab == ae) continue;
      for (const Offset& o : offsets) {
        const int64_t ny = y + o.dy, nz = z + o.dz;
        if (ny < 0 || ny >= d.ny || nz < 0) continue;
        const int64_t nrow = nz * d.ny + ny;
        LinkRows(set, ab, ae, set.RowBegin(nrow), set.RowBegin(nrow + 1), o.widen, &uf);
      }
    }
    if (z % 64 == 0) SM_RETURN_IF_ERROR(progress.Update(0.9 * (z + 1) / d.nz));
  }
  // Roots are each component's first run, so ordering by root breaks size ties by the
  // first voxel.
  std::vector<uint32_t> root_of(static_cast<size_t>(set.num_runs()));
  std::vector<uint64_t> root_size(static_cast<size_t>(set.num_runs()), 0);
  for (int64_t i = 0; i < set.num_runs(); ++i) {
    root_of[i] = uf.Find(static_cast<uint32_t>(i));
    root_size[root_of[i]] += set.run(i).length();
  }
  std::vector<uint32_t> roots;
  for (int64_t i = 0; i < set.num_runs(); ++i) {
    if (root_of[i] == static_cast<uint32_t>(i)) roots.push_back(static_cast<uint32_t>(i));
  }
  std::stable_sort(roots.begin(), roots.end(),
                   [&](uint32_t a, uint32_t b) { return root_size[a] > root_size[b]; });
  std::vector<uint32_t> label_of_root(static_cast<size_t>(set.num_runs()));
  Components c;
  c.sizes.reserve(roots.size());
  for (size_t k = 0; k < roots.size(); ++k) {
    label_of_root[roots[k]] = static_cast<uint32_t>(k);
    c.sizes.push_back(root_size[roots[k]]);
  }
  c.run_label.resize(static_cast<size_t>(set.num_runs()));
  for (int64_t i = 0; i < set.num_runs(); ++i) c.run_label[i] = label_of_root[root_of[i]];
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return c;
}

absl::StatusOr<RemovalResult> RemoveSmallComponents(const VoxelSet& set, uint64_t min_voxels,
                                                    Connectivity connectivity,
                                                    const Progress& progress) {
  RemovalResult result;
  if (min_voxels <= 1) {
    result.kept = set;
    return result;
  }
  SM_ASSIGN_OR_RETURN(Components c, LabelComponents(set, connectivity, progress));
  VoxelSet::Builder builder(set.dims());
  int64_t i = 0;
  set.ForEachRun([&](int32_t y, int32_t z, const Run& run, uint64_t) {
    if (c.sizes[c.run_label[i]] >= min_voxels) builder.AddRun(y, z, run.x0, run.x1);
    ++i;
  });
  for (uint64_t s : c.sizes) {
    if (s < min_voxels) {
      ++result.removed_components;
      result.removed_voxels += s;
    }
  }
  result.kept = std::move(builder).Build();
  return result;
}

}  // namespace sheetmesh
