#include "worker/pipeline/scvd/dual_triangles.h"

#include <nlohmann/json.hpp>

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "absl/container/inlined_vector.h"
#include "common/status_macros.h"
#include "worker/pipeline/mesh/spatial_grid.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/mesh/vertex_normals.h"
#include "worker/pipeline/scvd/rim_classifier.h"

namespace sheetmesh {
namespace {

struct Candidate {
  uint32_t a, b, c;  // sorted generator ids
  uint32_t amended;  // 1 if it came from an amended block
  bool operator<(const Candidate& o) const {
    if (a != o.a) return a < o.a;
    if (b != o.b) return b < o.b;
    if (c != o.c) return c < o.c;
    return amended < o.amended;
  }
  bool SameFace(const Candidate& o) const { return a == o.a && b == o.b && c == o.c; }
};

Candidate MakeCandidate(uint32_t x, uint32_t y, uint32_t z, uint32_t amended) {
  std::array<uint32_t, 3> t = {x, y, z};
  std::sort(t.begin(), t.end());
  return {t[0], t[1], t[2], amended};
}

uint64_t PairKey(uint32_t a, uint32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<uint64_t>(a) << 32) | b;
}

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

// Scans every 2x2x2 block (min corners from -1 to n-1, so that sheets on the box wall and
// one-voxel-thin sets have blocks) for three or more cells.
struct BlockScan {
  std::vector<Candidate> candidates;
  uint64_t three = 0, amended = 0, unresolved = 0;
};

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

struct Box {
  Vec3 lo, hi;
};

Box BoundsOf(const Triangle& t) {
  Box b;
  b.lo = {std::min({t[0].x, t[1].x, t[2].x}), std::min({t[0].y, t[1].y, t[2].y}),
          std::min({t[0].z, t[1].z, t[2].z})};
  b.hi = {std::max({t[0].x, t[1].x, t[2].x}), std::max({t[0].y, t[1].y, t[2].y}),
          std::max({t[0].z, t[1].z, t[2].z})};
  return b;
}

// Keeps faces that neither fold onto nor cut through the faces kept before them.
class FaceSelector {
 public:
  enum class Verdict { kKept, kDegenerate, kFold, kIntersection };

  FaceSelector(const std::vector<Vec3>* positions, double cell_size,
               const DualTriangleOptions& options)
      : pos_(positions), grid_(cell_size), options_(options) {}

  Verdict TryAdd(const Face& f) {
    const std::vector<Vec3>& pos = *pos_;
    const Triangle t = {pos[f[0]], pos[f[1]], pos[f[2]]};
    const double longest = std::max({Norm2(t[1] - t[0]), Norm2(t[2] - t[1]), Norm2(t[0] - t[2])});
    if (!(Norm(AreaVector(t)) > 1e-6 * longest) || MinAngleDegrees(t) < 0.5) {
      return Verdict::kDegenerate;
    }
    for (int k = 0; k < 3; ++k) {
      const uint32_t p = f[k], q = f[(k + 1) % 3], r = f[(k + 2) % 3];
      auto it = edge_faces_.find(PairKey(p, q));
      if (it == edge_faces_.end()) continue;
      for (uint32_t g : it->second) {
        const Face& h = faces_[g];
        const uint32_t s = h[0] != p && h[0] != q ? h[0] : (h[1] != p && h[1] != q ? h[1] : h[2]);
        if (s == r) return Verdict::kFold;  // the same triangle again
        if (DihedralAngleDegrees(pos[p], pos[q], pos[r], pos[s]) < options_.fold_angle_degrees) {
          return Verdict::kFold;
        }
      }
    }
    const Box box = BoundsOf(t);
    if (options_.reject_intersections) {
      bool hit = false;
      ++mark_;
      grid_.Query(box.lo, box.hi, [&](uint32_t g) {
        if (hit || stamp_[g] == mark_) return;
        stamp_[g] = mark_;
        const Face& h = faces_[g];
        int shared = 0;
        for (uint32_t u : f)
          for (uint32_t v : h) shared += u == v;
        if (shared >= 2) return;  // a shared edge was judged by the fold test
        hit = shared == 0 ? TrianglesIntersect(t, geom_[g])
                          : TrianglesIntersect(Shrink(t, 1e-3), Shrink(geom_[g], 1e-3));
      });
      if (hit) return Verdict::kIntersection;
    }
    const uint32_t id = static_cast<uint32_t>(faces_.size());
    faces_.push_back(f);
    geom_.push_back(t);
    stamp_.push_back(0);
    grid_.Insert(id, box.lo, box.hi);
    for (int k = 0; k < 3; ++k) edge_faces_[PairKey(f[k], f[(k + 1) % 3])].push_back(id);
    return Verdict::kKept;
  }

  const std::vector<Face>& faces() const { return faces_; }
  // Faces on edge (a, b).
  const absl::InlinedVector<uint32_t, 2>* EdgeFaces(uint32_t a, uint32_t b) const {
    auto it = edge_faces_.find(PairKey(a, b));
    return it == edge_faces_.end() ? nullptr : &it->second;
  }

 private:
  const std::vector<Vec3>* pos_;
  SpatialGrid grid_;
  DualTriangleOptions options_;
  absl::flat_hash_map<uint64_t, absl::InlinedVector<uint32_t, 2>> edge_faces_;
  std::vector<Face> faces_;
  std::vector<Triangle> geom_;
  std::vector<uint64_t> stamp_;
  uint64_t mark_ = 0;
};

void Count(FaceSelector::Verdict v, DualTriangleStats* stats) {
  switch (v) {
    case FaceSelector::Verdict::kKept:
      ++stats->kept;
      break;
    case FaceSelector::Verdict::kDegenerate:
      ++stats->rejected_degenerate;
      break;
    case FaceSelector::Verdict::kFold:
      ++stats->rejected_fold;
      break;
    case FaceSelector::Verdict::kIntersection:
      ++stats->rejected_intersection;
      break;
  }
}

// Rim vertices and the strip joining the mesh boundary to them (see DualTriangleOptions::rim).
void AddRim(const VoxelSet& set, const NeighborTable& neighbors,
            std::span<const uint16_t> thickness, const Scvd& scvd,
            const DualTriangleOptions& options, std::vector<Vec3>* pos, FaceSelector* selector,
            DualTriangulation* out) {
  const uint32_t num_gen = scvd.num_generators();
  // Boundary edges, directed as their one face walks them.
  std::vector<std::pair<uint32_t, uint32_t>> boundary;
  for (const Face& f : selector->faces()) {
    for (int k = 0; k < 3; ++k) {
      const auto* fs = selector->EdgeFaces(f[k], f[(k + 1) % 3]);
      if (fs != nullptr && fs->size() == 1) boundary.emplace_back(f[k], f[(k + 1) % 3]);
    }
  }
  if (boundary.empty()) return;
  std::vector<uint8_t> on_boundary(num_gen, 0);
  for (const auto& [p, q] : boundary) on_boundary[p] = on_boundary[q] = 1;
  // Normals of the generators (the faces are not oriented yet).
  const std::vector<Vec3> normal =
      VertexNormals(std::span<const Vec3>(pos->data(), num_gen), selector->faces());
  // Rim voxels of the boundary cells.
  const RimClassifier rim(set, options.rim_normal_cos);
  auto is_rim = [&](int32_t x, int32_t y, int32_t z, uint32_t c) {
    return rim.IsRim(x, y, z, normal[c]);
  };
  std::vector<Vec3> sum(num_gen);
  std::vector<double> tau(num_gen, 0.0);
  std::vector<uint32_t> count(num_gen, 0);
  set.ForEachVoxel([&](uint64_t v, int32_t x, int32_t y, int32_t z) {
    const uint32_t c = scvd.cell[v];
    if (c == kNoCell || !on_boundary[c] || !is_rim(x, y, z, c)) return;
    sum[c] += Vec3(x, y, z);
    tau[c] += thickness[v];
    ++count[c];
  });
  // Each boundary cell's rim vertex is the centroid of its outermost rim voxels: those
  // within half a voxel of the farthest along the direction from the generator to all its
  // rim voxels' centroid. A corner cell so reaches its corner, a straight rim keeps the
  // middle of the cell's stretch.
  std::vector<Vec3> centroid(num_gen), outward(num_gen);
  std::vector<double> best_out(num_gen, -1e300);
  for (uint32_t g = 0; g < num_gen; ++g) {
    if (count[g] == 0) continue;
    centroid[g] = sum[g] / count[g];
    Vec3 u = centroid[g] - (*pos)[g];
    u -= normal[g] * Dot(u, normal[g]);
    outward[g] = Normalized(u);
  }
  auto for_each_rim = [&](auto&& f) {
    set.ForEachVoxel([&](uint64_t v, int32_t x, int32_t y, int32_t z) {
      const uint32_t c = scvd.cell[v];
      if (c == kNoCell || !on_boundary[c] || count[c] == 0 || !is_rim(x, y, z, c)) {
        return;
      }
      f(c, Vec3(x, y, z));
    });
  };
  for_each_rim([&](uint32_t c, const Vec3& p) {
    best_out[c] = std::max(best_out[c], Dot(p - (*pos)[c], outward[c]));
  });
  std::vector<Vec3> outer_sum(num_gen);
  std::vector<uint32_t> outer_count(num_gen, 0);
  for_each_rim([&](uint32_t c, const Vec3& p) {
    if (Dot(p - (*pos)[c], outward[c]) >= best_out[c] - 0.5) {
      outer_sum[c] += p;
      ++outer_count[c];
    }
  });
  std::vector<uint32_t> rim_id(num_gen, UINT32_MAX);
  for (uint32_t g = 0; g < num_gen; ++g) {
    if (outer_count[g] == 0) continue;
    // Along the sheet: the outermost layer; across it: the depth of all the cell's rim
    // voxels, which span the thickness, so the vertex is at mid-depth even where the
    // outermost layer holds a few voxels on one wall.
    Vec3 q = outer_sum[g] / outer_count[g];
    q -= normal[g] * Dot(q - centroid[g], normal[g]);
    if (Norm2(q - (*pos)[g]) < 0.25) continue;  // the generator already sits on the rim
    rim_id[g] = static_cast<uint32_t>(pos->size());
    pos->push_back(q);
    out->rim_positions.push_back(q);
    out->rim_cell.push_back(g);
    out->rim_thickness.push_back(static_cast<float>(tau[g] / count[g]));
  }
  out->stats.rim_vertices = out->rim_positions.size();
  // The strip: for boundary edge p -> q, the quad q, p, Q_p, Q_q as two triangles walking
  // the edge as q -> p, so that orientation can agree with the face inside.
  for (const auto& [p, q] : boundary) {
    const uint32_t qp = rim_id[p], qq = rim_id[q];
    std::vector<Face> strip;
    if (qp != UINT32_MAX && qq != UINT32_MAX) {
      strip = {{q, p, qp}, {q, qp, qq}};
    } else if (qp != UINT32_MAX) {
      strip = {{q, p, qp}};
    } else if (qq != UINT32_MAX) {
      strip = {{q, p, qq}};
    }
    for (const Face& f : strip) {
      const FaceSelector::Verdict v = selector->TryAdd(f);
      Count(v, &out->stats);
      if (v == FaceSelector::Verdict::kKept) {
        ++out->stats.rim_faces;
        out->votes.push_back(0);
      }
    }
  }
}

// The fraction of the triangle's area whose nearest voxel is a sheet voxel, sampled on a
// grid of about half a voxel.
double SheetCoverage(const VoxelSet& set, const Triangle& t) {
  const double longest = std::max({Norm(t[1] - t[0]), Norm(t[2] - t[1]), Norm(t[0] - t[2])});
  const int n = std::max(2, static_cast<int>(std::ceil(longest * 2)));
  int inside = 0, total = 0;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; i + j <= n; ++j) {
      const double u = double(i) / n, v = double(j) / n;
      const Vec3 p = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
      ++total;
      inside += set.Contains(std::llround(p.x), std::llround(p.y), std::llround(p.z));
    }
  }
  return total > 0 ? double(inside) / total : 0.0;
}

// Closes cracks (see DualTriangleOptions::close_cracks), a few passes so that a notch
// closes ear by ear.
void CloseCracks(const VoxelSet& set, const DualTriangleOptions& options,
                 const std::vector<Vec3>& pos, FaceSelector* selector, DualTriangulation* out) {
  double edge_sum = 0;
  size_t edges = 0;
  for (const Face& f : selector->faces()) {
    for (int k = 0; k < 3; ++k) {
      edge_sum += Norm(pos[f[k]] - pos[f[(k + 1) % 3]]);
      ++edges;
    }
  }
  if (edges == 0) return;
  const double max_edge = 1.5 * edge_sum / edges;
  for (int pass = 0; pass < 4; ++pass) {
    // Boundary edges, directed as their one face walks them; the loop continues at the
    // edge leaving the end vertex.
    std::map<uint32_t, std::vector<uint32_t>> next;  // vertex -> boundary successors
    std::map<uint32_t, std::vector<uint32_t>> prev;
    for (const Face& f : selector->faces()) {
      for (int k = 0; k < 3; ++k) {
        const auto* fs = selector->EdgeFaces(f[k], f[(k + 1) % 3]);
        if (fs != nullptr && fs->size() == 1) {
          next[f[k]].push_back(f[(k + 1) % 3]);
          prev[f[(k + 1) % 3]].push_back(f[k]);
        }
      }
    }
    uint64_t closed = 0;
    for (const auto& [v, succ] : next) {
      // Only plain boundary vertices: one edge in, one edge out.
      if (succ.size() != 1 || prev[v].size() != 1) continue;
      const uint32_t w = succ[0], u = prev[v][0];
      if (u == w) continue;
      const Vec3 a = pos[u] - pos[v], b = pos[w] - pos[v];
      const double angle =
          std::acos(std::clamp(Dot(a, b) / (Norm(a) * Norm(b)), -1.0, 1.0)) * 180.0 / M_PI;
      if (angle >= options.crack_angle_degrees || Norm(pos[w] - pos[u]) > max_edge) continue;
      // The boundary runs u -> v -> w inside faces; the ear walks the edges the other way.
      const Face ear = {w, v, u};
      if (SheetCoverage(set, {pos[u], pos[v], pos[w]}) < 0.5) continue;
      if (selector->TryAdd(ear) == FaceSelector::Verdict::kKept) {
        ++closed;
        ++out->stats.crack_faces;
        ++out->stats.kept;
        out->votes.push_back(0);
      }
    }
    if (closed == 0) break;
  }
}

}  // namespace

absl::StatusOr<DualTriangulation> TriangulateScvd(const VoxelSet& set,
                                                  const NeighborTable& neighbors,
                                                  std::span<const uint16_t> thickness,
                                                  const Scvd& scvd, std::span<const Vec3> positions,
                                                  const DualTriangleOptions& options,
                                                  const Progress& progress) {
  DualTriangulation result;
  if (positions.size() != scvd.num_generators()) {
    return absl::InvalidArgumentError("one vertex position per generator is required");
  }
  absl::flat_hash_set<uint64_t> adjacency;
  adjacency.reserve(scvd.adjacency.size());
  for (const auto& [a, b] : scvd.adjacency) adjacency.insert(PairKey(a, b));

  const Dims& d = set.dims();
  const size_t plane = static_cast<size_t>((d.nx + 2) * (d.ny + 2));
  tbb::combinable<BlockScan> scans;
  tbb::parallel_for(tbb::blocked_range<int64_t>(-1, d.nz),
                    [&](const tbb::blocked_range<int64_t>& r) {
                      std::vector<uint32_t> lo(plane, kNoCell), hi(plane, kNoCell);
                      BlockScan& out = scans.local();
                      for (int64_t z = r.begin(); z < r.end(); ++z) {
                        ScanSlicePair(set, scvd, z, &lo, &hi, adjacency, positions, &out);
                      }
                    });
  std::vector<Candidate> all;
  scans.combine_each([&](BlockScan& s) {
    result.stats.blocks_three += s.three;
    result.stats.blocks_amended += s.amended;
    result.stats.blocks_unresolved += s.unresolved;
    all.insert(all.end(), s.candidates.begin(), s.candidates.end());
    s.candidates = {};
  });
  SM_RETURN_IF_ERROR(progress.Update(0.4));
  tbb::parallel_sort(all.begin(), all.end());

  // One candidate per generator triple, with its votes; a triple that any plain block gave
  // counts as plain.
  struct Ranked {
    Candidate c;
    uint32_t votes;
    double min_angle;
  };
  std::vector<Ranked> ranked;
  for (size_t i = 0; i < all.size();) {
    size_t j = i;
    uint32_t plain = 0;
    while (j < all.size() && all[j].SameFace(all[i])) {
      plain += all[j].amended == 0;
      ++j;
    }
    Candidate c = all[i];
    c.amended = plain > 0 ? 0 : 1;
    const Triangle t = {positions[c.a], positions[c.b], positions[c.c]};
    ranked.push_back({c, static_cast<uint32_t>(j - i), MinAngleDegrees(t)});
    i = j;
  }
  all = {};
  result.stats.candidates = ranked.size();
  std::sort(ranked.begin(), ranked.end(), [](const Ranked& x, const Ranked& y) {
    if (x.votes != y.votes) return x.votes > y.votes;
    if (x.c.amended != y.c.amended) return x.c.amended < y.c.amended;
    if (x.min_angle != y.min_angle) return x.min_angle > y.min_angle;
    return x.c < y.c;
  });

  // Greedy selection, most-voted first.
  double edge_sum = 0;
  for (const Ranked& r : ranked) edge_sum += Norm(positions[r.c.a] - positions[r.c.b]);
  const double cell = std::max(1.0, 2.0 * edge_sum / std::max<size_t>(1, ranked.size()));
  std::vector<Vec3> pos(positions.begin(), positions.end());
  FaceSelector selector(&pos, cell, options);
  for (size_t i = 0; i < ranked.size(); ++i) {
    if ((i & 0xFFFF) == 0) SM_RETURN_IF_ERROR(progress.Update(0.4 + 0.5 * i / ranked.size()));
    const Candidate& c = ranked[i].c;
    const FaceSelector::Verdict v = selector.TryAdd({c.a, c.b, c.c});
    Count(v, &result.stats);
    if (v == FaceSelector::Verdict::kKept) result.votes.push_back(ranked[i].votes);
  }
  if (options.close_cracks) CloseCracks(set, options, pos, &selector, &result);
  if (options.rim) AddRim(set, neighbors, thickness, scvd, options, &pos, &selector, &result);
  result.faces = selector.faces();
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return result;
}

nlohmann::json DualTriangleStats::Fields() const {
  return {{"candidates", candidates},
          {"blocks_three_cells", blocks_three},
          {"blocks_amended", blocks_amended},
          {"blocks_unresolved", blocks_unresolved},
          {"kept", kept},
          {"rejected_fold", rejected_fold},
          {"rejected_intersection", rejected_intersection},
          {"rejected_degenerate", rejected_degenerate},
          {"rim_vertices", rim_vertices},
          {"rim_triangles", rim_faces},
          {"crack_triangles", crack_faces}};
}

}  // namespace sheetmesh
