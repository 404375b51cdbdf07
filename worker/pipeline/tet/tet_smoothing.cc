#include "worker/pipeline/tet/tet_smoothing.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "worker/pipeline/tet/tet_improve.h"
#include "worker/pipeline/tet/tet_quality.h"

namespace sheetmesh {

double BlendedShape(const TetMeshEditor& ed, const Tet& t, double q, double radius_weight) {
  if (radius_weight == 0) return q;
  const double ra = RadiusAspect(ed.P(t[0]), ed.P(t[1]), ed.P(t[2]), ed.P(t[3]));
  return (1 - radius_weight) * q + radius_weight * kRegularDihedral * ra;
}

bool SmoothVertex(TetMeshEditor& ed, const VertexFreedom& fr, uint32_t v,
                  const SmoothingOptions& options) {
  auto Shape = [&](const Tet& t, double q) {
    return BlendedShape(ed, t, q, options.radius_weight);
  };
  if (!fr.may_move(v)) return false;
  const std::vector<uint32_t>& star = ed.star(v);
  const Vec3 start = ed.node(v);
  double cur_min = 1e300, cur_sum = 0, length = 0;
  std::vector<uint32_t> ring;
  for (uint32_t t : star) {
    cur_min = std::min(cur_min, ed.quality(t));
    cur_sum += Shape(ed.tet(t), ed.quality(t));
    for (uint32_t w : ed.tet(t)) {
      if (w != v) ring.push_back(w);
    }
  }
  std::sort(ring.begin(), ring.end());
  ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  Vec3 centroid{0, 0, 0};
  for (uint32_t w : ring) {
    centroid += ed.node(w);
    length += Norm(ed.node(w) - start);
  }
  centroid = centroid / static_cast<double>(ring.size());
  length /= static_cast<double>(ring.size());
  auto masked = [&](const Vec3& d) { return fr.Constrain(v, d); };
  // The star's worst and mean at p.
  auto eval = [&](const Vec3& p, double* mn, double* sum) {
    ed.node(v) = p;
    *mn = 1e300;
    *sum = 0;
    for (uint32_t t : star) {
      const double q = ed.Quality(ed.tet(t));
      *mn = std::min(*mn, q);
      *sum += Shape(ed.tet(t), q);
      if (q < 0) break;
    }
    ed.node(v) = start;
  };
  Vec3 best = start;
  bool moved = false;
  // Backtracking along dir from best: the first step (halving from max_step) whose star
  // (worst, sum) `accept` takes becomes the new best.
  auto search = [&](const Vec3& dir, double max_step, auto accept) {
    for (double step = max_step; step > 1e-3 * length; step *= 0.5) {
      const Vec3 p = fr.Place(v, best + dir * step);
      double mn, sum;
      eval(p, &mn, &sum);
      if (accept(mn, sum)) {
        best = p;
        cur_min = mn;
        cur_sum = sum;
        moved = true;
        return true;
      }
    }
    return false;
  };
  // A candidate position is taken if it raises the star's worst, or its sum without
  // lowering the worst below the floor (or below where it already is).
  auto take_if_better = [&](const Vec3& target) {
    const Vec3 p = fr.Place(v, start + masked(target - start));
    double mn, sum;
    eval(p, &mn, &sum);
    if (mn > cur_min + kGain ||
        (mn >= std::min(cur_min, options.floor_degrees) && sum > cur_sum + kGain)) {
      best = p;
      cur_min = mn;
      cur_sum = sum;
      moved = true;
    }
  };
  take_if_better(centroid);
  // The optimal-Delaunay position: the volume-weighted mean of the star's circumcentres.
  {
    Vec3 odt{0, 0, 0};
    double weight = 0;
    for (uint32_t t : star) {
      const Tet& x = ed.tet(t);
      const double volume = TetVolume(ed.P(x[0]), ed.P(x[1]), ed.P(x[2]), ed.P(x[3]));
      Vec3 cc;
      if (!(volume > 0) || !Circumcentre(ed.P(x[0]), ed.P(x[1]), ed.P(x[2]), ed.P(x[3]), &cc))
        continue;
      odt += cc * volume;
      weight += volume;
    }
    if (weight > 0) take_if_better(odt / weight);
  }
  // Ascent on the worst tetrahedra: the direction that raises the two worst together.
  for (int iter = 0; iter < 8; ++iter) {
    ed.node(v) = best;
    uint32_t worst[2] = {UINT32_MAX, UINT32_MAX};
    double wq[2] = {1e300, 1e300};
    for (uint32_t t : star) {
      const double q = ed.Quality(ed.tet(t));
      if (q < wq[0]) {
        worst[1] = worst[0];
        wq[1] = wq[0];
        worst[0] = t;
        wq[0] = q;
      } else if (q < wq[1]) {
        worst[1] = t;
        wq[1] = q;
      }
    }
    const double h = 1e-5 * length;
    Vec3 g[2];
    for (int w = 0; w < 2; ++w) {
      if (worst[w] == UINT32_MAX) continue;
      for (int k = 0; k < 3; ++k) {
        g[w][k] = 0;
        if (!fr.Varies(v, k)) continue;
        Vec3 p = best;
        p[k] += h;
        ed.node(v) = p;
        const double up = ed.Quality(ed.tet(worst[w]));
        p[k] = best[k] - h;
        ed.node(v) = p;
        const double down = ed.Quality(ed.tet(worst[w]));
        g[w][k] = (up - down) / (2 * h);
      }
      g[w] = masked(g[w]);
    }
    ed.node(v) = start;
    Vec3 dir = g[0];
    if (worst[1] != UINT32_MAX && wq[1] < wq[0] + 1.0) {
      // The point of the segment between the two gradients nearest the origin.
      const Vec3 diff = g[0] - g[1];
      const double d2 = Norm2(diff);
      const double s = d2 > 0 ? std::clamp(Dot(g[0], diff) / d2, 0.0, 1.0) : 0.0;
      // Opposite gradients cancel to rounding noise off the allowed moves: constrain the
      // result again, and stop where it is no real direction.
      dir = masked(g[0] - diff * s);
    }
    const double dn = Norm(dir);
    if (!(dn > 1e-9 * Norm(g[0]))) break;
    dir = dir / dn;
    if (!search(dir, 0.2 * length, [&](double mn, double) { return mn > cur_min + kGain; })) {
      break;
    }
  }
  // Then ascent on the star's mean, never lowering its worst.
  for (int iter = 0; iter < 6; ++iter) {
    const double h = 1e-5 * length;
    Vec3 g{0, 0, 0};
    for (int k = 0; k < 3; ++k) {
      if (!fr.Varies(v, k)) continue;
      Vec3 p = best;
      double mn, up, down;
      p[k] += h;
      eval(p, &mn, &up);
      p[k] = best[k] - h;
      eval(p, &mn, &down);
      g[k] = (up - down) / (2 * h);
    }
    g = masked(g);
    const double gn = Norm(g);
    if (!(gn > 0)) break;
    if (!search(g / gn, 0.1 * length, [&](double mn, double sum) {
          return mn >= std::min(cur_min, options.floor_degrees) && sum > cur_sum + kGain;
        })) {
      break;
    }
  }
  ed.node(v) = best;
  if (moved) {
    for (uint32_t t : star) ed.Remeasure(t);
  }
  return moved;
}

}  // namespace sheetmesh
