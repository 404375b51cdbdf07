#include <algorithm>
#include <cmath>
#include <limits>

#include "worker/pipeline/scvd/dual_triangles_parts.h"

namespace sheetmesh {
namespace {

// The amending strategy (Fig. 9): the cells of a block form a polygon along the adjacency
// edges recorded while growing. Among the Hamiltonian cycles of the block's adjacency
// graph, the shortest is the polygon; it is triangulated by the diagonals of least total
// length (for a quadrilateral: the shorter diagonal, Fig. 9(f)). Blocks whose cells form
// no cycle give the triangles of their adjacency cliques instead. Returns false when
// nothing could be made.
bool Amend(const absl::InlinedVector<uint32_t, 8>& cells,
           const absl::flat_hash_set<uint64_t>& adjacency, std::span<const Vec3> pos,
           std::vector<Candidate>* out) {
  const int k = static_cast<int>(cells.size());
  bool adj[8][8] = {};
  for (int i = 0; i < k; ++i)
    for (int j = i + 1; j < k; ++j)
      adj[i][j] = adj[j][i] = adjacency.contains(PairKey(cells[i], cells[j]));
  // Hamiltonian cycles with vertex 0 first: permute the rest.
  std::array<int, 8> perm, best;
  for (int i = 0; i < k; ++i) perm[i] = i;
  double best_len = std::numeric_limits<double>::max();
  do {
    if (perm[1] > perm[k - 1]) continue;  // each cycle once, not in both directions
    double len = 0;
    bool ok = true;
    for (int i = 0; i < k && ok; ++i) {
      const int u = perm[i], v = perm[(i + 1) % k];
      ok = adj[u][v];
      len += Norm(pos[cells[u]] - pos[cells[v]]);
    }
    if (ok && len < best_len) {
      best_len = len;
      best = perm;
    }
  } while (std::next_permutation(perm.begin() + 1, perm.begin() + k));
  if (best_len == std::numeric_limits<double>::max()) {
    bool any = false;
    for (int i = 0; i < k; ++i)
      for (int j = i + 1; j < k; ++j)
        for (int l = j + 1; l < k; ++l)
          if (adj[i][j] && adj[j][l] && adj[i][l]) {
            out->push_back(MakeCandidate(cells[i], cells[j], cells[l], 1));
            any = true;
          }
    return any;
  }
  // Minimum-weight triangulation of the polygon by dynamic programming over its chords.
  std::array<Vec3, 8> p;
  for (int i = 0; i < k; ++i) p[i] = pos[cells[best[i]]];
  double cost[8][8] = {};
  int split[8][8] = {};
  for (int gap = 2; gap < k; ++gap) {
    for (int i = 0; i + gap < k; ++i) {
      const int j = i + gap;
      cost[i][j] = std::numeric_limits<double>::max();
      for (int m = i + 1; m < j; ++m) {
        // Chords are the sides (i, m) and (m, j) that are not polygon edges.
        const double c = cost[i][m] + cost[m][j] + (m - i > 1 ? Norm(p[i] - p[m]) : 0) +
                         (j - m > 1 ? Norm(p[m] - p[j]) : 0);
        if (c < cost[i][j]) {
          cost[i][j] = c;
          split[i][j] = m;
        }
      }
    }
  }
  std::vector<std::pair<int, int>> stack = {{0, k - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    const int m = split[i][j];
    out->push_back(MakeCandidate(cells[best[i]], cells[best[m]], cells[best[j]], 1));
    stack.push_back({i, m});
    stack.push_back({m, j});
  }
  return true;
}

}  // namespace

void ScanSlicePair(const VoxelSet& set, const Scvd& scvd, int64_t z, std::vector<uint32_t>* lo,
                   std::vector<uint32_t>* hi, const absl::flat_hash_set<uint64_t>& adjacency,
                   std::span<const Vec3> pos, BlockScan* out) {
  const Dims& d = set.dims();
  const int64_t w = d.nx + 2;  // planes are padded by one voxel on each side in x and y
  auto fill = [&](std::vector<uint32_t>* plane, int64_t zz, bool set_labels) {
    if (zz < 0 || zz >= d.nz) return;
    for (int64_t y = 0; y < d.ny; ++y) {
      const int64_t row = set.RowId(y, zz);
      for (int64_t i = set.RowBegin(row); i < set.RowBegin(row + 1); ++i) {
        const Run& r = set.run(i);
        const uint64_t first = set.RunFirstIndex(i);
        uint32_t* dst = plane->data() + (y + 1) * w + 1;
        for (int32_t x = r.x0; x < r.x1; ++x) {
          dst[x] = set_labels ? scvd.cell[first + (x - r.x0)] : kNoCell;
        }
      }
    }
  };
  fill(lo, z, true);
  fill(hi, z + 1, true);
  std::vector<Run> rows;
  absl::InlinedVector<uint32_t, 8> cells;
  for (int64_t y = -1; y < d.ny; ++y) {
    // Block min corners (x, y, z) whose blocks touch a voxel: x in [x0 - 1, x1 - 1].
    rows.clear();
    for (int64_t yy : {y, y + 1}) {
      if (yy < 0 || yy >= d.ny) continue;
      for (int64_t zz : {z, z + 1}) {
        if (zz < 0 || zz >= d.nz) continue;
        for (const Run& r : set.RowRuns(yy, zz)) rows.push_back({r.x0 - 1, r.x1});
      }
    }
    if (rows.empty()) continue;
    std::sort(rows.begin(), rows.end(), [](const Run& a, const Run& b) { return a.x0 < b.x0; });
    int32_t done = std::numeric_limits<int32_t>::min();
    for (const Run& r : rows) {
      for (int32_t x = std::max(r.x0, done); x < r.x1; ++x) {
        cells.clear();
        for (int dz = 0; dz < 2; ++dz) {
          const uint32_t* plane = (dz == 0 ? lo : hi)->data();
          for (int dy = 0; dy < 2; ++dy) {
            const uint32_t* row = plane + (y + dy + 1) * w + 1;
            for (int dx = 0; dx < 2; ++dx) {
              const uint32_t c = row[x + dx];
              if (c != kNoCell && std::find(cells.begin(), cells.end(), c) == cells.end()) {
                cells.push_back(c);
              }
            }
          }
        }
        if (cells.size() == 3) {
          ++out->three;
          out->candidates.push_back(MakeCandidate(cells[0], cells[1], cells[2], 0));
        } else if (cells.size() >= 4) {
          ++out->amended;
          if (!Amend(cells, adjacency, pos, &out->candidates)) ++out->unresolved;
        }
      }
      done = std::max(done, r.x1);
    }
  }
  fill(lo, z, false);
  fill(hi, z + 1, false);
}

}  // namespace sheetmesh
