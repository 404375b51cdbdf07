#include "worker/pipeline/tet/tet_flips.h"

#include <algorithm>
#include <array>
#include <utility>
#include <vector>

#include "worker/pipeline/tet/tet_quality.h"

namespace sheetmesh {
namespace {

constexpr int kMaxRing = 7;  // edge removal looks at rings of 3..7 tetrahedra

}  // namespace

bool RemoveEdge(TetMeshEditor& ed, uint32_t u, uint32_t v, double mean, int max_added) {
  std::array<uint32_t, kMaxRing> ids;
  size_t m = 0;
  for (uint32_t t : ed.star(u)) {
    if (!Has(ed.tet(t), v)) continue;
    if (m == kMaxRing) return false;
    ids[m++] = t;
  }
  if (m < 3 || static_cast<int>(m) - 4 > max_added) return false;
  // Each tetrahedron (u, v, x, y) gives the ring edge x -> y, directed so that the
  // tetrahedron is positive; the edges of an interior edge's ring form one cycle.
  std::array<std::pair<uint32_t, uint32_t>, kMaxRing> edges;
  double current = 1e300;
  for (size_t i = 0; i < m; ++i) {
    const Tet& t = ed.tet(ids[i]);
    uint32_t other[2], k = 0;
    for (uint32_t w : t) {
      if (w != u && w != v) other[k++] = w;
    }
    if (ed.IsFacetFace(SortedFace(u, v, other[0])) || ed.IsFacetFace(SortedFace(u, v, other[1]))) {
      return false;
    }
    if (TetVolume(ed.P(u), ed.P(v), ed.P(other[0]), ed.P(other[1])) < 0)
      std::swap(other[0], other[1]);
    edges[i] = {other[0], other[1]};
    current = std::min(current, ed.quality(ids[i]));
  }
  std::array<uint32_t, kMaxRing> ring;
  std::array<bool, kMaxRing> used{};
  ring[0] = edges[0].first;
  uint32_t at = edges[0].first;
  for (size_t k = 0; k < m; ++k) {
    size_t e = m;
    for (size_t i = 0; i < m; ++i) {
      if (!used[i] && edges[i].first == at) {
        e = i;
        break;
      }
    }
    if (e == m) return false;  // an open ring: the edge is on the boundary
    used[e] = true;
    at = edges[e].second;
    if (k + 1 < m) {
      ring[k + 1] = at;
    } else if (at != ring[0]) {
      return false;
    }
  }
  // Optimal triangulation of the ring polygon by dynamic programming over its chords.
  const bool by_mean = mean >= 0;
  double before = 0;
  for (size_t i = 0; i < m; ++i) before += ed.quality(ids[i]) - mean;
  double best[kMaxRing][kMaxRing];
  int split[kMaxRing][kMaxRing];
  constexpr double kNone = -1e300;
  for (size_t i = 0; i + 1 < m; ++i) best[i][i + 1] = by_mean ? 0 : 1e300;
  for (size_t len = 2; len < m; ++len) {
    for (size_t i = 0; i + len < m; ++i) {
      const size_t j = i + len;
      best[i][j] = kNone;
      split[i][j] = -1;
      for (size_t k = i + 1; k < j; ++k) {
        if (best[i][k] == kNone || best[k][j] == kNone) continue;
        if (!by_mean && std::min(best[i][k], best[k][j]) <= best[i][j]) continue;
        // Triangle (ring i, k, j) is counter-clockwise seen from v.
        const double qv = MinDihedralDegrees(ed.P(ring[i]), ed.P(ring[k]), ed.P(ring[j]), ed.P(v));
        if (!(qv > (by_mean ? current : best[i][j]))) continue;
        const double qu = MinDihedralDegrees(ed.P(ring[k]), ed.P(ring[i]), ed.P(ring[j]), ed.P(u));
        if (!(qu > (by_mean ? current : best[i][j]))) continue;
        const double val = by_mean ? best[i][k] + best[k][j] + (qv - mean) + (qu - mean)
                                   : std::min({best[i][k], best[k][j], qv, qu});
        if (val > best[i][j]) {
          best[i][j] = val;
          split[i][j] = static_cast<int>(k);
        }
      }
    }
  }
  if (best[0][m - 1] == kNone) return false;
  if (!(best[0][m - 1] > (by_mean ? before : current) + kGain)) return false;
  for (size_t i = 0; i < m; ++i) ed.Kill(ids[i]);
  std::vector<std::pair<size_t, size_t>> todo = {{0, m - 1}};
  while (!todo.empty()) {
    const auto [i, j] = todo.back();
    todo.pop_back();
    if (j < i + 2) continue;
    const size_t k = split[i][j];
    ed.Add({ring[i], ring[k], ring[j], v});
    ed.Add({ring[k], ring[i], ring[j], u});
    todo.push_back({i, k});
    todo.push_back({k, j});
  }
  return true;
}

bool RemoveFace(TetMeshEditor& ed, uint32_t t, int f, double mean, int max_added) {
  if (max_added < 1) return false;
  const Tet tet = ed.tet(t);
  const uint32_t d = tet[f];
  uint32_t a = tet[(f + 1) % 4], b = tet[(f + 2) % 4], c = tet[(f + 3) % 4];
  if (ed.IsFacetFace(SortedFace(a, b, c))) return false;
  if (TetVolume(ed.P(a), ed.P(b), ed.P(c), ed.P(d)) < 0) std::swap(a, b);
  uint32_t n = UINT32_MAX;
  for (uint32_t s : ed.star(a)) {
    if (s != t && Has(ed.tet(s), b) && Has(ed.tet(s), c)) {
      n = s;
      break;
    }
  }
  if (n == UINT32_MAX) return false;  // a boundary face
  uint32_t e = 0;
  for (uint32_t w : ed.tet(n)) {
    if (w != a && w != b && w != c) e = w;
  }
  const double current = std::min(ed.quality(t), ed.quality(n));
  const Tet nt[3] = {{a, b, e, d}, {b, c, e, d}, {c, a, e, d}};
  double after = 0;
  for (const Tet& x : nt) {
    const double q = ed.Quality(x);
    if (!(q > current + (mean >= 0 ? 0 : kGain))) return false;
    after += q - mean;
  }
  if (mean >= 0 && !(after > ed.quality(t) + ed.quality(n) - 2 * mean + kGain)) return false;
  ed.Kill(t);
  ed.Kill(n);
  for (const Tet& x : nt) ed.Add(x);
  return true;
}

Flip FlipAround(TetMeshEditor& ed, uint32_t t, double mean, int max_added) {
  const Tet tet = ed.tet(t);
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) {
      if (RemoveEdge(ed, tet[a], tet[b], mean, max_added)) return Flip::kEdge;
    }
  for (int f = 0; f < 4; ++f) {
    if (RemoveFace(ed, t, f, mean, max_added)) return Flip::kFace;
  }
  return Flip::kNone;
}

}  // namespace sheetmesh
