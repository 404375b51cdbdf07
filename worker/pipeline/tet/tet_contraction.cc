#include "worker/pipeline/tet/tet_contraction.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "absl/container/flat_hash_set.h"
#include "worker/pipeline/tet/tet_quality.h"

namespace sheetmesh {
namespace {

using TetKey = std::array<uint32_t, 4>;

TetKey Sorted(Tet t) {
  std::sort(t.begin(), t.end());
  return t;
}

}  // namespace

bool ContractEdgeOf(TetMeshEditor& ed, const VertexFreedom& freedom, uint32_t t) {
  const Tet tet = ed.tet(t);
  uint32_t best_u = UINT32_MAX;
  std::vector<Tet> best_fill, fill;
  double best = -1e300;
  for (const uint32_t u : tet) {
    if (!freedom.interior(u)) continue;
    const std::vector<uint32_t> star = ed.star(u);
    double worst = 1e300, volume = 0;
    for (uint32_t s : star) {
      const Tet& x = ed.tet(s);
      worst = std::min(worst, ed.quality(s));
      volume += TetVolume(ed.P(x[0]), ed.P(x[1]), ed.P(x[2]), ed.P(x[3]));
    }
    for (const uint32_t w : tet) {
      if (w == u) continue;
      // What w's star holds already: a new tetrahedron equal to one of them would be a
      // fold (u's star and w's overlapping), not a contraction.
      absl::flat_hash_set<TetKey> around_w;
      for (uint32_t s : ed.star(w)) {
        if (!Has(ed.tet(s), u)) around_w.insert(Sorted(ed.tet(s)));
      }
      double now = 1e300, filled = 0;
      bool valid = true;
      fill.clear();
      for (uint32_t s : star) {
        Tet x = ed.tet(s);
        if (Has(x, w)) continue;
        for (uint32_t& c : x) c = c == u ? w : c;
        fill.push_back(x);
        const double v = TetVolume(ed.P(x[0]), ed.P(x[1]), ed.P(x[2]), ed.P(x[3]));
        if (!(v > 1e-12 * volume) || around_w.contains(Sorted(x))) {
          valid = false;
          break;
        }
        filled += v;
        now = std::min(now, ed.Quality(x));
        if (!(now > worst + kGain) || !(now > best)) {
          valid = false;
          break;
        }
      }
      // The new tetrahedra, all positive, must fill u's star exactly; more would mean two
      // of them overlap.
      if (!valid || !(std::abs(filled - volume) <= 1e-9 * volume)) continue;
      best = now;
      best_u = u;
      best_fill.swap(fill);
    }
  }
  if (best_u == UINT32_MAX) return false;
  const std::vector<uint32_t> star = ed.star(best_u);
  for (uint32_t s : star) ed.Kill(s);
  for (const Tet& x : best_fill) ed.Add(x);
  return true;
}

}  // namespace sheetmesh
