#include "worker/pipeline/tet/tet_smoothing.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/status_macros.h"
#include "worker/pipeline/tet/tet_quality.h"

namespace sheetmesh {

double BlendedShape(const TetMeshEditor& ed, const Tet& t, double q, double radius_weight) {
  if (radius_weight == 0) return q;
  const double ra = RadiusAspect(ed.P(t[0]), ed.P(t[1]), ed.P(t[2]), ed.P(t[3]));
  return (1 - radius_weight) * q + radius_weight * kRegularDihedral * ra;
}

namespace {

// One vertex's smoothing: its star, where it started, the best position so far and that
// position's worst quality and sum of shapes.
class Smoother {
 public:
  Smoother(TetMeshEditor& ed, const VertexFreedom& fr, uint32_t v, const SmoothingOptions& o)
      : ed_(ed), fr_(fr), v_(v), o_(o), star_(ed.star(v)), start_(ed.node(v)), best_(start_) {
    std::vector<uint32_t> ring;
    for (uint32_t t : star_) {
      cur_min_ = std::min(cur_min_, ed_.quality(t));
      cur_sum_ += Shape(ed_.tet(t), ed_.quality(t));
      for (uint32_t w : ed_.tet(t)) {
        if (w != v_) ring.push_back(w);
      }
    }
    std::sort(ring.begin(), ring.end());
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    for (uint32_t w : ring) {
      centroid_ += ed_.node(w);
      length_ += Norm(ed_.node(w) - start_);
    }
    centroid_ = centroid_ / static_cast<double>(ring.size());
    length_ /= static_cast<double>(ring.size());
  }

  // Tries the ring's centroid and the optimal-Delaunay point, then climbs: first the worst
  // tetrahedra, then the mean (a PLC sheet vertex within its ball: the worst only). Leaves the
  // vertex at the best position; true if it moved (the caller measures the star again). Reads the
  // vertex's star and its ring and writes only the vertex's position.
  bool Run() {
    if (fr_.in_ball(v_)) {
      // A PLC sheet vertex: the sheet moves with it, for its worst tetrahedra only.
      AscendWorst();
      ed_.node(v_) = best_;
      return moved_;
    }
    TakeIfBetter(centroid_);
    TakeOptimalDelaunay();
    AscendWorst();
    AscendMean();
    ed_.node(v_) = best_;
    return moved_;
  }

 private:
  double Shape(const Tet& t, double q) const { return BlendedShape(ed_, t, q, o_.radius_weight); }
  Vec3 Masked(const Vec3& d) const { return fr_.Constrain(v_, d); }

  // The star's worst and sum of shapes with the vertex at p. A position with a tetrahedron
  // under `reject_below` is refused whatever its sum, so the count stops there (its `mn` is
  // under that bound, its sum left partial); so it does at an inverted tetrahedron, whose
  // shape still counts. The angles come first and the shapes, which cost as much again,
  // only for a position not refused.
  void Eval(const Vec3& p, double* mn, double* sum, double reject_below = -1e300) {
    ed_.node(v_) = p;
    *mn = 1e300;
    *sum = 0;
    size_t n = 0;
    q_.resize(star_.size());
    bool refused = false;
    for (uint32_t t : star_) {
      const double q = ed_.Quality(ed_.tet(t));
      q_[n++] = q;
      *mn = std::min(*mn, q);
      if (q < reject_below) {
        refused = true;
        break;
      }
      if (q < 0) break;
    }
    if (!refused) {
      for (size_t i = 0; i < n; ++i) *sum += Shape(ed_.tet(star_[i]), q_[i]);
    }
    ed_.node(v_) = start_;
  }

  void Take(const Vec3& p, double mn, double sum) {
    best_ = p;
    cur_min_ = mn;
    cur_sum_ = sum;
    moved_ = true;
  }

  // Backtracking along dir from the best: the first step (halving from max_step) whose
  // star (worst, sum) `accept` takes becomes the new best; `accept` never takes a worst
  // under `reject_below` (Eval stops counting there).
  template <class Accept>
  bool Search(const Vec3& dir, double max_step, double reject_below, Accept accept) {
    for (double step = max_step; step > 1e-3 * length_; step *= 0.5) {
      const Vec3 p = fr_.Place(v_, best_ + dir * step);
      double mn, sum;
      Eval(p, &mn, &sum, reject_below);
      if (accept(mn, sum)) {
        Take(p, mn, sum);
        return true;
      }
    }
    return false;
  }

  // A candidate position is taken if it raises the star's worst, or its sum without
  // lowering the worst below the floor (or below where it already is).
  void TakeIfBetter(const Vec3& target) {
    const Vec3 p = fr_.Place(v_, start_ + Masked(target - start_));
    double mn, sum;
    Eval(p, &mn, &sum, std::min(cur_min_, o_.floor_degrees));
    if (mn > cur_min_ + kGain ||
        (mn >= std::min(cur_min_, o_.floor_degrees) && sum > cur_sum_ + kGain)) {
      Take(p, mn, sum);
    }
  }

  // The optimal-Delaunay position: the volume-weighted mean of the star's circumcentres.
  void TakeOptimalDelaunay() {
    Vec3 odt{0, 0, 0};
    double weight = 0;
    for (uint32_t t : star_) {
      const Tet& x = ed_.tet(t);
      const double volume = TetVolume(ed_.P(x[0]), ed_.P(x[1]), ed_.P(x[2]), ed_.P(x[3]));
      Vec3 cc;
      if (!(volume > 0) || !Circumcentre(ed_.P(x[0]), ed_.P(x[1]), ed_.P(x[2]), ed_.P(x[3]), &cc))
        continue;
      odt += cc * volume;
      weight += volume;
    }
    if (weight > 0) TakeIfBetter(odt / weight);
  }

  // Ascent on the worst tetrahedra: the direction that raises the two worst together.
  void AscendWorst() {
    for (int iter = 0; iter < 8; ++iter) {
      ed_.node(v_) = best_;
      uint32_t worst[2] = {UINT32_MAX, UINT32_MAX};
      double wq[2] = {1e300, 1e300};
      for (uint32_t t : star_) {
        const double q = ed_.Quality(ed_.tet(t));
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
      const double h = 1e-5 * length_;
      Vec3 g[2];
      for (int w = 0; w < 2; ++w) {
        if (worst[w] == UINT32_MAX) continue;
        for (int k = 0; k < 3; ++k) {
          g[w][k] = 0;
          if (!fr_.Varies(v_, k)) continue;
          Vec3 p = best_;
          p[k] += h;
          ed_.node(v_) = p;
          const double up = ed_.Quality(ed_.tet(worst[w]));
          p[k] = best_[k] - h;
          ed_.node(v_) = p;
          const double down = ed_.Quality(ed_.tet(worst[w]));
          g[w][k] = (up - down) / (2 * h);
        }
        g[w] = Masked(g[w]);
      }
      ed_.node(v_) = start_;
      Vec3 dir = g[0];
      if (worst[1] != UINT32_MAX && wq[1] < wq[0] + 1.0) {
        // The point of the segment between the two gradients nearest the origin.
        const Vec3 diff = g[0] - g[1];
        const double d2 = Norm2(diff);
        const double s = d2 > 0 ? std::clamp(Dot(g[0], diff) / d2, 0.0, 1.0) : 0.0;
        // Opposite gradients cancel to rounding noise off the allowed moves: constrain the
        // result again, and stop where it is no real direction.
        dir = Masked(g[0] - diff * s);
      }
      const double dn = Norm(dir);
      if (!(dn > 1e-9 * Norm(g[0]))) break;
      dir = dir / dn;
      if (!Search(dir, 0.2 * length_, cur_min_ + kGain,
                  [&](double mn, double) { return mn > cur_min_ + kGain; })) {
        break;
      }
    }
  }

  // Ascent on the star's mean, never lowering its worst.
  void AscendMean() {
    for (int iter = 0; iter < 6; ++iter) {
      const double h = 1e-5 * length_;
      Vec3 g{0, 0, 0};
      for (int k = 0; k < 3; ++k) {
        if (!fr_.Varies(v_, k)) continue;
        Vec3 p = best_;
        double mn, up, down;
        p[k] += h;
        Eval(p, &mn, &up);
        p[k] = best_[k] - h;
        Eval(p, &mn, &down);
        g[k] = (up - down) / (2 * h);
      }
      g = Masked(g);
      const double gn = Norm(g);
      if (!(gn > 0)) break;
      if (!Search(g / gn, 0.1 * length_, std::min(cur_min_, o_.floor_degrees),
                  [&](double mn, double sum) {
                    return mn >= std::min(cur_min_, o_.floor_degrees) && sum > cur_sum_ + kGain;
                  })) {
        break;
      }
    }
  }

  TetMeshEditor& ed_;
  const VertexFreedom& fr_;
  const uint32_t v_;
  const SmoothingOptions o_;
  const std::vector<uint32_t>& star_;
  const Vec3 start_;
  Vec3 best_;
  Vec3 centroid_{0, 0, 0};
  double cur_min_ = 1e300, cur_sum_ = 0, length_ = 0;
  bool moved_ = false;
  std::vector<double> q_;  // Eval's angles, star order
};

void MeasureStar(TetMeshEditor& ed, uint32_t v) {
  for (uint32_t t : ed.star(v)) ed.Remeasure(t);
}

}  // namespace

bool SmoothVertex(TetMeshEditor& ed, const VertexFreedom& fr, uint32_t v,
                  const SmoothingOptions& options) {
  if (!fr.may_move(v) || !Smoother(ed, fr, v, options).Run()) return false;
  MeasureStar(ed, v);
  return true;
}

absl::Status SmoothVertices(TetMeshEditor& ed, const VertexFreedom& fr, std::vector<uint32_t> todo,
                            const SmoothingOptions& options,
                            const std::function<bool(uint32_t)>& wants,
                            const std::function<void(uint32_t, bool)>& done,
                            const Progress& progress) {
  std::vector<uint32_t> taken_in(ed.num_nodes(), 0);  // the round that took v or a neighbour
  std::vector<uint32_t> round, waiting;
  std::vector<uint8_t> moved;
  const size_t total = todo.size();
  size_t finished = 0;
  for (uint32_t r = 1; !todo.empty(); ++r) {
    round.clear();
    waiting.clear();
    for (uint32_t v : todo) {
      if (taken_in[v] == r) {
        waiting.push_back(v);
        continue;
      }
      ++finished;
      if (!wants(v)) continue;
      round.push_back(v);
      for (uint32_t t : ed.star(v))
        for (uint32_t w : ed.tet(t)) taken_in[w] = r;
    }
    moved.assign(round.size(), 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, round.size(), 8),
                      [&](const tbb::blocked_range<size_t>& range) {
                        for (size_t i = range.begin(); i != range.end(); ++i) {
                          moved[i] = Smoother(ed, fr, round[i], options).Run();
                        }
                      });
    for (size_t i = 0; i < round.size(); ++i) {
      if (moved[i]) MeasureStar(ed, round[i]);
      done(round[i], moved[i] != 0);
    }
    todo.swap(waiting);
    SM_RETURN_IF_ERROR(
        progress.Tick(static_cast<int64_t>(finished), static_cast<int64_t>(total), 1));
  }
  return absl::OkStatus();
}

}  // namespace sheetmesh
