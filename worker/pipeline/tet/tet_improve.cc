#include "worker/pipeline/tet/tet_improve.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <utility>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "absl/time/clock.h"
#include "worker/pipeline/tet/tet_quality.h"

namespace sheetmesh {

double MinDihedralDegrees(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Vec3 ab = b - a, ac = c - a, ad = d - a;
  if (Dot(Cross(ab, ac), ad) <= 0) return -1.0;
  // Outward normals of the faces opposite d, c, b and a (the tetrahedron is positive).
  Vec3 n[4] = {Cross(ac, ab), Cross(ab, ad), Cross(ad, ac), Cross(c - b, d - b)};
  for (Vec3& v : n) {
    const double len = Norm(v);
    if (!(len > 0)) return -1.0;
    v = v / len;
  }
  // The dihedral angle between faces i and j is π minus the angle between their normals;
  // the smallest angle has the largest -n_i·n_j.
  double worst = -1.0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) worst = std::max(worst, -Dot(n[i], n[j]));
  return std::acos(std::clamp(worst, -1.0, 1.0)) * (180.0 / std::numbers::pi);
}

nlohmann::json TetImproveReport::Fields() const {
  return {{"passes", passes},
          {"edge_removals", edge_removals},
          {"face_removals", face_removals},
          {"smoothing_moves", smoothing_moves},
          {"inserted_vertices", inserted_vertices},
          {"sheet_face_splits", sheet_face_splits},
          {"sheet_edge_splits", sheet_edge_splits},
          {"movable_vertices", movable_vertices},
          {"sliding_vertices", sliding_vertices},
          {"min_dihedral_before", min_dihedral_before},
          {"mean_dihedral_before", mean_dihedral_before},
          {"min_dihedral_after", min_dihedral_after},
          {"mean_dihedral_after", mean_dihedral_after},
          {"seconds", seconds}};
}

namespace {

// The set's members in increasing order: hash-set order changes from run to run, and the
// result must not.
std::vector<uint32_t> Sorted(const absl::flat_hash_set<uint32_t>& set) {
  std::vector<uint32_t> v(set.begin(), set.end());
  std::sort(v.begin(), v.end());
  return v;
}

bool Has(const Tet& t, uint32_t v) { return t[0] == v || t[1] == v || t[2] == v || t[3] == v; }

constexpr double kRegularDihedral = 70.528779365509308;  // acos(1/3), degrees
constexpr double kGain = 1e-6;  // degrees: the least rise that counts as an improvement
constexpr int kMaxRing = 7;     // edge removal looks at rings of 3..7 tetrahedra
// Below this, insertion tries many more points (26 more directions and a closer one).
constexpr double kWideSearchDegrees = 15.0;

class Improver {
 public:
  Improver(TetMesh* mesh, const Vec3& lo, const Vec3& hi, uint32_t input_nodes,
           const TetImproveOptions& options)
      : m_(*mesh),
        floor_(options.smoothing_floor_degrees),
        radius_weight_(options.radius_weight),
        split_below_(options.split_sheets_below_degrees) {
    const size_t n = m_.nodes.size();
    star_.resize(n);
    q_.resize(m_.tets.size());
    dead_.assign(m_.tets.size(), 0);
    failed_.assign(m_.tets.size(), 0);
    for (uint32_t t = 0; t < m_.tets.size(); ++t) {
      for (uint32_t v : m_.tets[t]) star_[v].push_back(t);
      q_[t] = Quality(m_.tets[t]);
    }
    // Which coordinates each vertex may change: none on a sheet; on the box, not the ones
    // that put it on a box face.
    mask_.assign(n, 7);
    const Vec3 ext = hi - lo;
    const double tol = 1e-9 * std::max({std::abs(ext.x), std::abs(ext.y), std::abs(ext.z)});
    for (size_t v = 0; v < n; ++v) {
      for (int k = 0; k < 3; ++k) {
        const double x = m_.nodes[v][k];
        if (std::abs(x - lo[k]) <= tol || std::abs(x - hi[k]) <= tol) mask_[v] &= ~(1 << k);
      }
    }
    const std::vector<uint8_t> off_box = mask_;
    sheet_faces_of_.resize(n);
    for (uint32_t f = 0; f < m_.faces.size(); ++f) {
      const auto& face = m_.faces[f];
      constrained_[SortedFace(face[0], face[1], face[2])] = f;
      if (m_.face_piece[f] >= 0) {
        for (uint32_t v : face) {
          mask_[v] = 0;
          sheet_faces_of_[v].push_back(f);
        }
      }
    }
    ClassifySheetNodes(input_nodes, off_box);
  }

  uint32_t movable() const {
    uint32_t n = 0;
    for (uint32_t v = 0; v < mask_.size(); ++v) n += may_move(v);
    return n;
  }
  uint32_t sliding() const {
    return static_cast<uint32_t>(
        std::count_if(slide_.begin(), slide_.end(), [](Slide s) { return s != Slide::kNone; }));
  }

  std::pair<double, double> MinMean() const {
    double mn = 1e300, sum = 0;
    size_t count = 0;
    for (size_t t = 0; t < q_.size(); ++t) {
      if (dead_[t]) continue;
      mn = std::min(mn, q_[t]);
      sum += q_[t];
      ++count;
    }
    return {count ? mn : 0.0, count ? sum / count : 0.0};
  }

  // Tetrahedra below `target`, worst first.
  std::vector<uint32_t> Bad(double target) const {
    std::vector<uint32_t> bad;
    for (uint32_t t = 0; t < q_.size(); ++t) {
      if (!dead_[t] && q_[t] < target) bad.push_back(t);
    }
    std::sort(bad.begin(), bad.end(), [&](uint32_t a, uint32_t b) { return q_[a] < q_[b]; });
    return bad;
  }

  bool alive(uint32_t t) const { return !dead_[t]; }
  uint32_t num_nodes() const { return static_cast<uint32_t>(m_.nodes.size()); }
  double quality(uint32_t t) const { return q_[t]; }
  const Tet& tet(uint32_t t) const { return m_.tets[t]; }
  bool may_move(uint32_t v) const { return mask_[v] != 0 || slide_[v] != Slide::kNone; }
  double StarMin(uint32_t v) const {
    double mn = 1e300;
    for (uint32_t t : star_[v]) mn = std::min(mn, q_[t]);
    return mn;
  }

  // Replaces the tetrahedra around the edge (u, v) by the best triangulation of the ring of
  // their other vertices, each triangle joined to u and to v (Shewchuk's edge removal).
  // With mean < 0 "best" raises the worst tetrahedron; otherwise it raises the sum of
  // (quality - mean), i.e. the mesh's mean quality, without going below the old worst.
  bool RemoveEdge(uint32_t u, uint32_t v, double mean = -1) {
    std::array<uint32_t, kMaxRing> ids;
    size_t m = 0;
    for (uint32_t t : star_[u]) {
      if (!Has(m_.tets[t], v)) continue;
      if (m == kMaxRing) return false;
      ids[m++] = t;
    }
    if (m < 3) return false;
    // Each tetrahedron (u, v, x, y) gives the ring edge x -> y, directed so that the
    // tetrahedron is positive; the edges of an interior edge's ring form one cycle.
    std::array<std::pair<uint32_t, uint32_t>, kMaxRing> edges;
    double current = 1e300;
    for (size_t i = 0; i < m; ++i) {
      const Tet& t = m_.tets[ids[i]];
      uint32_t other[2], k = 0;
      for (uint32_t w : t) {
        if (w != u && w != v) other[k++] = w;
      }
      if (constrained_.contains(SortedFace(u, v, other[0])) ||
          constrained_.contains(SortedFace(u, v, other[1]))) {
        return false;
      }
      if (TetVolume(P(u), P(v), P(other[0]), P(other[1])) < 0) std::swap(other[0], other[1]);
      edges[i] = {other[0], other[1]};
      current = std::min(current, q_[ids[i]]);
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
    for (size_t i = 0; i < m; ++i) before += q_[ids[i]] - mean;
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
          const double qv = MinDihedralDegrees(P(ring[i]), P(ring[k]), P(ring[j]), P(v));
          if (!(qv > (by_mean ? current : best[i][j]))) continue;
          const double qu = MinDihedralDegrees(P(ring[k]), P(ring[i]), P(ring[j]), P(u));
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
    for (size_t i = 0; i < m; ++i) Kill(ids[i]);
    std::vector<std::pair<size_t, size_t>> todo = {{0, m - 1}};
    while (!todo.empty()) {
      const auto [i, j] = todo.back();
      todo.pop_back();
      if (j < i + 2) continue;
      const size_t k = split[i][j];
      Add({ring[i], ring[k], ring[j], v});
      Add({ring[k], ring[i], ring[j], u});
      todo.push_back({i, k});
      todo.push_back({k, j});
    }
    return true;
  }

  // The 2-3 flip of the face of tetrahedron t opposite its vertex `f`; `mean` as for
  // RemoveEdge.
  bool RemoveFace(uint32_t t, int f, double mean = -1) {
    const Tet tet = m_.tets[t];
    const uint32_t d = tet[f];
    uint32_t a = tet[(f + 1) % 4], b = tet[(f + 2) % 4], c = tet[(f + 3) % 4];
    if (constrained_.contains(SortedFace(a, b, c))) return false;
    if (TetVolume(P(a), P(b), P(c), P(d)) < 0) std::swap(a, b);
    uint32_t n = UINT32_MAX;
    for (uint32_t s : star_[a]) {
      if (s != t && Has(m_.tets[s], b) && Has(m_.tets[s], c)) {
        n = s;
        break;
      }
    }
    if (n == UINT32_MAX) return false;  // a boundary face
    uint32_t e = 0;
    for (uint32_t w : m_.tets[n]) {
      if (w != a && w != b && w != c) e = w;
    }
    const double current = std::min(q_[t], q_[n]);
    const Tet nt[3] = {{a, b, e, d}, {b, c, e, d}, {c, a, e, d}};
    double after = 0;
    for (const Tet& x : nt) {
      const double q = Quality(x);
      if (!(q > current + (mean >= 0 ? 0 : kGain))) return false;
      after += q - mean;
    }
    if (mean >= 0 && !(after > q_[t] + q_[n] - 2 * mean + kGain)) return false;
    Kill(t);
    Kill(n);
    for (const Tet& x : nt) Add(x);
    return true;
  }

  // Moves vertex v (within the coordinates it may change) to raise the smallest dihedral
  // angle of its star, or, keeping that, the star's mean.
  bool Smooth(uint32_t v) {
    if (!may_move(v)) return false;
    const std::vector<uint32_t>& star = star_[v];
    const Vec3 start = m_.nodes[v];
    double cur_min = 1e300, cur_sum = 0, length = 0;
    std::vector<uint32_t> ring;
    for (uint32_t t : star) {
      cur_min = std::min(cur_min, q_[t]);
      cur_sum += Shape(m_.tets[t], q_[t]);
      for (uint32_t w : m_.tets[t]) {
        if (w != v) ring.push_back(w);
      }
    }
    std::sort(ring.begin(), ring.end());
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    Vec3 centroid{0, 0, 0};
    for (uint32_t w : ring) {
      centroid += m_.nodes[w];
      length += Norm(m_.nodes[w] - start);
    }
    centroid = centroid / static_cast<double>(ring.size());
    length /= static_cast<double>(ring.size());
    auto masked = [&](const Vec3& d) { return Constrain(v, d); };
    // The star's worst and mean at p.
    auto eval = [&](const Vec3& p, double* mn, double* sum) {
      m_.nodes[v] = p;
      *mn = 1e300;
      *sum = 0;
      for (uint32_t t : star) {
        const double q = Quality(m_.tets[t]);
        *mn = std::min(*mn, q);
        *sum += Shape(m_.tets[t], q);
        if (q < 0) break;
      }
      m_.nodes[v] = start;
    };
    Vec3 best = start;
    bool moved = false;
    // Backtracking along dir from best: the first step (halving from max_step) whose star
    // (worst, sum) `accept` takes becomes the new best.
    auto search = [&](const Vec3& dir, double max_step, auto accept) {
      for (double step = max_step; step > 1e-3 * length; step *= 0.5) {
        const Vec3 p = Place(v, best + dir * step);
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
      const Vec3 p = Place(v, start + masked(target - start));
      double mn, sum;
      eval(p, &mn, &sum);
      if (mn > cur_min + kGain || (mn >= std::min(cur_min, floor_) && sum > cur_sum + kGain)) {
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
        const Tet& x = m_.tets[t];
        const double volume = TetVolume(P(x[0]), P(x[1]), P(x[2]), P(x[3]));
        Vec3 cc;
        if (!(volume > 0) || !Circumcentre(P(x[0]), P(x[1]), P(x[2]), P(x[3]), &cc)) continue;
        odt += cc * volume;
        weight += volume;
      }
      if (weight > 0) take_if_better(odt / weight);
    }
    // Ascent on the worst tetrahedra: the direction that raises the two worst together.
    for (int iter = 0; iter < 8; ++iter) {
      m_.nodes[v] = best;
      uint32_t worst[2] = {UINT32_MAX, UINT32_MAX};
      double wq[2] = {1e300, 1e300};
      for (uint32_t t : star) {
        const double q = Quality(m_.tets[t]);
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
          if (!Varies(v, k)) continue;
          Vec3 p = best;
          p[k] += h;
          m_.nodes[v] = p;
          const double up = Quality(m_.tets[worst[w]]);
          p[k] = best[k] - h;
          m_.nodes[v] = p;
          const double down = Quality(m_.tets[worst[w]]);
          g[w][k] = (up - down) / (2 * h);
        }
        g[w] = masked(g[w]);
      }
      m_.nodes[v] = start;
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
        if (!Varies(v, k)) continue;
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
            return mn >= std::min(cur_min, floor_) && sum > cur_sum + kGain;
          })) {
        break;
      }
    }
    m_.nodes[v] = best;
    if (moved) {
      for (uint32_t t : star) {
        q_[t] = Quality(m_.tets[t]);
        failed_[t] = 0;
      }
    }
    return moved;
  }

  // Inserts a new vertex off the sliver t, on one side of its plane, into the cavity of
  // the tetrahedra around it (those whose circumsphere holds the point, grown or shrunk
  // until every face of the cavity's boundary sees the point, never across a facet), then
  // smooths it. Kept only if the cavity's worst tetrahedron improves.
  bool InsertNear(uint32_t t) {
    // A sliver whose corners have not moved since its last failed try fails again (nearly
    // always): most of the pass's time went into such retries.
    if (failed_[t]) return false;
    failed_[t] = 1;
    const Tet tet = m_.tets[t];
    // The new vertex goes inside the facets the sliver lies on (the sum of their inward
    // normals); in a crease of a sheet that may hide the facets of the slivers next to it,
    // so the facets of its neighbours count in a second try. A sliver on no facet tries
    // both sides of its largest face.
    Vec3 own{0, 0, 0}, near{0, 0, 0}, largest{0, 0, 0};
    auto facet_normals = [&](uint32_t x, Vec3* sum) {
      bool any = false;
      for (int f = 0; f < 4; ++f) {
        const auto face = InwardFace(x, f);
        if (!constrained_.contains(SortedFace(face[0], face[1], face[2]))) continue;
        const Vec3 normal = Cross(P(face[1]) - P(face[0]), P(face[2]) - P(face[0]));
        if (!(Norm2(normal) > 0)) continue;
        *sum += Normalized(normal);
        any = true;
      }
      return any;
    };
    const bool on_facet = facet_normals(t, &own);
    near = own;
    for (int f = 0; f < 4; ++f) {
      const auto face = InwardFace(t, f);
      const Vec3 normal = Cross(P(face[1]) - P(face[0]), P(face[2]) - P(face[0]));
      if (Norm2(normal) > Norm2(largest)) largest = normal;
      const uint32_t y = Neighbor(t, f);
      if (y != UINT32_MAX && !constrained_.contains(TetFace(tet, f))) facet_normals(y, &near);
    }
    std::vector<Vec3> directions;
    for (const Vec3& d : on_facet ? std::vector<Vec3>{own, near}
                                  : std::vector<Vec3>{largest, largest * -1.0, near}) {
      if (!(Norm2(d) > 0)) continue;
      const Vec3 u = Normalized(d);
      if (std::none_of(directions.begin(), directions.end(),
                       [&](const Vec3& e) { return Dot(e, u) > 1 - 1e-6; })) {
        directions.push_back(u);
      }
    }
    double length = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) length += Norm(P(tet[i]) - P(tet[j]));
    length /= 6;
    const Vec3 centre = (P(tet[0]) + P(tet[1]) + P(tet[2]) + P(tet[3])) / 4.0;
    // The worst tetrahedra (a handful per mesh, wedged between sheets) also try the 26
    // directions of a cube's faces, edges and corners.
    std::vector<double> heights = {0.7, 0.45, 0.25};
    if (q_[t] < kWideSearchDegrees) {
      for (int x = -1; x <= 1; ++x)
        for (int y = -1; y <= 1; ++y)
          for (int z = -1; z <= 1; ++z) {
            if (x || y || z) directions.push_back(Normalized(Vec3(x, y, z)));
          }
      heights.push_back(0.12);
    }
    Candidate best;
    for (const Vec3& n : directions) {
      for (double h : heights) {
        Candidate c;
        c.p = centre + n * (h * length);
        if (!Cavity(t, c.p, &c.cavity, &c.fill)) continue;
        c.quality = 1e300;
        for (const Tet& x : c.fill) {
          c.quality = std::min(c.quality, MinDihedralDegrees(P(x[0]), P(x[1]), P(x[2]), c.p));
        }
        if (c.quality > best.quality) best = std::move(c);
      }
    }
    auto gain = [&](const Candidate& c) {
      double current = 1e300;
      for (uint32_t x : c.cavity) current = std::min(current, q_[x]);
      return c.quality - current;
    };
    // Where no point off the sheets lifts the sliver above split_below_, its corners are
    // pinned by the sheets around it; a point on a sheet face or edge near it may do better.
    if ((best.cavity.empty() || !(gain(best) > kGain) || best.quality < split_below_) &&
        q_[t] < split_below_) {
      Candidate split = BestSheetSplit(t);
      if (!split.cavity.empty() && gain(split) > kGain && split.quality > best.quality) {
        best = std::move(split);
      }
    }
    if (best.cavity.empty() || !(gain(best) > kGain)) return false;
    Apply(best);
    return true;
  }

  // A candidate new vertex: its cavity and fill; for a point on a sheet, the sheet faces it
  // splits (indices into m_.faces) and, on a sheet edge, that edge.
  struct Candidate {
    Vec3 p;
    std::vector<uint32_t> cavity;
    std::vector<Tet> fill;
    double quality = -1e300;  // the fill's worst tetrahedron
    std::vector<uint32_t> split;
    std::array<uint32_t, 2> edge = {UINT32_MAX, UINT32_MAX};
  };

  // The best point on a sheet face or sheet edge of, or next to, sliver t: inside each sheet
  // face holding an edge of t, a grid of ten points and the feet of t's other corners; on
  // each sheet edge of t (not on the box), five points along it and the feet of t's other
  // two corners. The cavity must hold t.
  // Such a point splits the face (into three) or every face on the edge (each into two), so
  // the sheet faces still tile the input triangles.
  Candidate BestSheetSplit(uint32_t t) {
    const Tet tet = m_.tets[t];
    Candidate best;
    auto consider = [&](Candidate c, const std::vector<uint32_t>& seeds,
                        const absl::flat_hash_set<FaceKey>& opened) {
      std::vector<std::pair<uint32_t, uint32_t>> keep;
      for (uint32_t f : c.split) {
        const auto& face = m_.faces[f];
        for (int i = 0; i < 3; ++i) {
          const auto e = std::minmax(face[i], face[(i + 1) % 3]);
          if (e != std::minmax(c.edge[0], c.edge[1])) keep.push_back(e);
        }
      }
      if (!GrowCavity(c.p, seeds, opened, keep, &c.cavity, &c.fill)) return;
      // Every split face's new pieces must be faces of the fill: each edge of a piece that
      // does not end at p must be an edge of the cavity's boundary.
      absl::flat_hash_set<std::pair<uint32_t, uint32_t>> rim;
      for (const Tet& x : c.fill) {
        for (int i = 0; i < 3; ++i) {
          rim.insert(std::minmax(x[i], x[(i + 1) % 3]));
        }
      }
      for (const auto& e : keep) {
        if (!rim.contains(e)) return;
      }
      c.quality = 1e300;
      for (const Tet& x : c.fill) {
        c.quality = std::min(c.quality, MinDihedralDegrees(P(x[0]), P(x[1]), P(x[2]), c.p));
      }
      if (c.quality > best.quality) best = std::move(c);
    };
    // Sheet faces holding an edge of t.
    std::vector<uint32_t> faces;
    for (uint32_t v : tet) {
      for (uint32_t f : sheet_faces_of_[v]) {
        int shared = 0;
        for (uint32_t w : m_.faces[f]) shared += Has(tet, w);
        if (shared >= 2) faces.push_back(f);
      }
    }
    std::sort(faces.begin(), faces.end());
    faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
    for (uint32_t f : faces) {
      const auto face = m_.faces[f];
      const Vec3 a = P(face[0]), b = P(face[1]), c = P(face[2]);
      const Vec3 normal = Cross(b - a, c - a);
      const double area2 = Norm2(normal);
      if (!(area2 > 0)) continue;
      const FaceKey key = SortedFace(face[0], face[1], face[2]);
      std::vector<uint32_t> seeds;
      for (uint32_t s : star_[face[0]]) {
        if (Has(m_.tets[s], face[1]) && Has(m_.tets[s], face[2])) seeds.push_back(s);
      }
      if (seeds.size() != 2) continue;
      // The sliver must go: it is a seed of the cavity too.
      if (seeds[0] != t && seeds[1] != t) seeds.push_back(t);
      // A grid of points well inside the face (barycentric sixths, none on an edge).
      std::vector<Vec3> points;
      for (int i = 1; i <= 4; ++i)
        for (int j = 1; i + j <= 5; ++j) points.push_back((a * i + b * j + c * (6 - i - j)) / 6.0);
      for (uint32_t w : tet) {
        if (w == face[0] || w == face[1] || w == face[2]) continue;
        // Barycentric coordinates of w's foot, kept 0.15 inside every edge.
        const Vec3 q = P(w);
        double l[3] = {Dot(Cross(c - b, q - b), normal) / area2,
                       Dot(Cross(a - c, q - c), normal) / area2, 0};
        l[2] = 1 - l[0] - l[1];
        double sum = 0;
        for (double& x : l) {
          x = std::max(x, 0.15);
          sum += x;
        }
        points.push_back((a * l[0] + b * l[1] + c * l[2]) / sum);
      }
      for (const Vec3& p : points) {
        Candidate cand;
        cand.p = p;
        cand.split = {f};
        consider(std::move(cand), seeds, {key});
      }
    }
    // Sheet edges of t.
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) {
        const uint32_t u = tet[i], w = tet[j];
        std::vector<uint32_t> split;
        bool on_box = false;
        for (uint32_t f : sheet_faces_of_[u]) {
          const auto& face = m_.faces[f];
          if (face[0] == w || face[1] == w || face[2] == w) split.push_back(f);
        }
        if (split.empty()) continue;
        std::vector<uint32_t> ring;
        absl::flat_hash_set<FaceKey> opened;
        for (uint32_t s : star_[u]) {
          if (!Has(m_.tets[s], w)) continue;
          ring.push_back(s);
          for (int f = 0; f < 4; ++f) {
            const FaceKey key = TetFace(m_.tets[s], f);
            const bool holds = std::find(key.begin(), key.end(), u) != key.end() &&
                               std::find(key.begin(), key.end(), w) != key.end();
            if (!holds) continue;
            const auto it = constrained_.find(key);
            if (it == constrained_.end()) continue;
            if (m_.face_piece[it->second] < 0) on_box = true;
            opened.insert(key);
          }
        }
        if (on_box || opened.size() != split.size()) continue;
        const Vec3 a = P(u), d = P(w) - P(u);
        const double len2 = Norm2(d);
        if (!(len2 > 0)) continue;
        std::vector<double> along = {0.25, 0.375, 0.5, 0.625, 0.75};
        for (uint32_t x : tet) {
          if (x != u && x != w) along.push_back(std::clamp(Dot(P(x) - a, d) / len2, 0.2, 0.8));
        }
        for (double s : along) {
          Candidate cand;
          cand.p = a + d * s;
          cand.split = split;
          cand.edge = {u, w};
          consider(std::move(cand), ring, opened);
        }
      }
    return best;
  }

  // Inserts the candidate's vertex: its cavity's tetrahedra replaced by the fill; on a
  // sheet, each split face replaced by its pieces (same input triangle, piece and
  // thickness, same orientation) and the vertex free to slide in that face or edge.
  void Apply(const Candidate& c) {
    const uint32_t v = static_cast<uint32_t>(m_.nodes.size());
    m_.nodes.push_back(c.p);
    star_.emplace_back();
    sheet_faces_of_.emplace_back();
    anchor_.push_back(c.p);
    if (c.split.empty()) {
      mask_.push_back(7);
      slide_.push_back(Slide::kNone);
      axis_.push_back({0, 0, 0});
    } else if (c.edge[0] == UINT32_MAX) {
      const auto& face = m_.faces[c.split[0]];
      mask_.push_back(0);
      slide_.push_back(Slide::kPlane);
      axis_.push_back(Normalized(Cross(P(face[1]) - P(face[0]), P(face[2]) - P(face[0]))));
      ++facet_splits_;
    } else {
      mask_.push_back(0);
      slide_.push_back(Slide::kLine);
      axis_.push_back(Normalized(P(c.edge[1]) - P(c.edge[0])));
      ++edge_splits_;
    }
    for (uint32_t x : c.cavity) Kill(x);
    for (Tet x : c.fill) {
      x[3] = v;
      Add(x);
    }
    for (uint32_t f : c.split) {
      const std::array<uint32_t, 3> face = m_.faces[f];
      constrained_.erase(SortedFace(face[0], face[1], face[2]));
      for (uint32_t w : face) {
        auto& of = sheet_faces_of_[w];
        of.erase(std::remove(of.begin(), of.end(), f), of.end());
      }
      std::vector<std::array<uint32_t, 3>> pieces;
      for (int i = 0; i < 3; ++i) {
        std::array<uint32_t, 3> piece = face;
        if (c.edge[0] == UINT32_MAX) {
          piece[(i + 2) % 3] = v;  // (face[i], face[i + 1], v)
        } else if (face[i] == c.edge[0] || face[i] == c.edge[1]) {
          piece[i] = v;
        } else {
          continue;
        }
        pieces.push_back(piece);
      }
      for (size_t k = 0; k < pieces.size(); ++k) {
        uint32_t index = f;
        if (k == 0) {
          m_.faces[f] = pieces[k];
        } else {
          index = static_cast<uint32_t>(m_.faces.size());
          const int32_t marker = m_.face_marker[f], piece = m_.face_piece[f];
          const float thickness = m_.face_thickness[f];
          m_.faces.push_back(pieces[k]);
          m_.face_marker.push_back(marker);
          m_.face_piece.push_back(piece);
          m_.face_thickness.push_back(thickness);
        }
        constrained_[SortedFace(pieces[k][0], pieces[k][1], pieces[k][2])] = index;
        for (uint32_t w : pieces[k]) sheet_faces_of_[w].push_back(index);
      }
    }
    Smooth(v);
  }

  uint64_t facet_splits() const { return facet_splits_; }
  uint64_t edge_splits() const { return edge_splits_; }

  // Writes the live tetrahedra back into the mesh.
  void Finish() {
    size_t out = 0;
    for (size_t t = 0; t < m_.tets.size(); ++t) {
      if (!dead_[t]) m_.tets[out++] = m_.tets[t];
    }
    m_.tets.resize(out);
  }

 private:
  // How a sheet vertex TetGen added may move: within the sheet triangle it lies inside
  // (in the plane of normal axis_), or along the sheet edge it lies on (direction axis_).
  // Either way the sheet's faces still tile the input triangles, as long as no tetrahedron
  // inverts, which every move checks.
  enum class Slide : uint8_t { kNone, kPlane, kLine };

  const Vec3& P(uint32_t v) const { return m_.nodes[v]; }

  // d restricted to the moves vertex v may make.
  Vec3 Constrain(uint32_t v, Vec3 d) const {
    switch (slide_[v]) {
      case Slide::kPlane:
        return d - axis_[v] * Dot(d, axis_[v]);
      case Slide::kLine:
        return axis_[v] * Dot(d, axis_[v]);
      case Slide::kNone:
        break;
    }
    for (int k = 0; k < 3; ++k) {
      if (!(mask_[v] & (1 << k))) d[k] = 0;
    }
    return d;
  }
  // p put back exactly on v's plane or line (through its first position). Constrain alone
  // leaves rounding noise of the size of the move's discarded part, which can be large (an
  // optimal-Delaunay point far off a sheet), and it would add up over moves.
  Vec3 Place(uint32_t v, const Vec3& p) const {
    switch (slide_[v]) {
      case Slide::kPlane:
        return p - axis_[v] * Dot(p - anchor_[v], axis_[v]);
      case Slide::kLine:
        return anchor_[v] + axis_[v] * Dot(p - anchor_[v], axis_[v]);
      case Slide::kNone:
        break;
    }
    return p;
  }
  // Whether coordinate k of v can change at all (a partial derivative worth taking).
  bool Varies(uint32_t v, int k) const {
    return slide_[v] != Slide::kNone || (mask_[v] & (1 << k));
  }

  // Finds the sheet vertices TetGen added (ids from input_nodes on) that may slide: one
  // whose sheet faces all belong to one input triangle and close a fan around it lies inside
  // that triangle; one whose fans (one per input triangle) each open onto two neighbours on
  // one line through it lies on an input edge. Vertices on the box stay where they are.
  // off_box[v] == 7: v lies on no box plane.
  void ClassifySheetNodes(uint32_t input_nodes, const std::vector<uint8_t>& off_box) {
    slide_.assign(m_.nodes.size(), Slide::kNone);
    axis_.assign(m_.nodes.size(), Vec3{0, 0, 0});
    anchor_ = m_.nodes;
    // Per vertex: (input triangle marker, one of its faces); vertices on the box.
    std::vector<std::vector<std::pair<int32_t, uint32_t>>> faces_of(m_.nodes.size());
    std::vector<uint8_t> on_box(m_.nodes.size(), 0);
    for (uint32_t f = 0; f < m_.faces.size(); ++f) {
      for (uint32_t v : m_.faces[f]) {
        if (m_.face_piece[f] < 0) {
          on_box[v] = 1;
        } else {
          faces_of[v].push_back({m_.face_marker[f], f});
        }
      }
    }
    for (uint32_t v = input_nodes; v < m_.nodes.size(); ++v) {
      auto& fs = faces_of[v];
      if (fs.empty() || on_box[v] || off_box[v] != 7) continue;
      std::sort(fs.begin(), fs.end());
      std::vector<uint32_t> open;  // neighbours across the fans' open ends
      size_t groups = 0;
      Vec3 normal{0, 0, 0};
      for (size_t i = 0; i < fs.size();) {
        size_t j = i;
        std::vector<uint32_t> ends;
        while (j < fs.size() && fs[j].first == fs[i].first) {
          const auto& face = m_.faces[fs[j].second];
          for (uint32_t w : face) {
            if (w != v) ends.push_back(w);
          }
          const Vec3 n = Cross(P(face[1]) - P(face[0]), P(face[2]) - P(face[0]));
          if (Norm2(n) > Norm2(normal)) normal = n;
          ++j;
        }
        std::sort(ends.begin(), ends.end());
        for (size_t k = 0; k < ends.size();) {
          size_t l = k;
          while (l < ends.size() && ends[l] == ends[k]) ++l;
          if (l - k == 1) open.push_back(ends[k]);
          k = l;
        }
        ++groups;
        i = j;
      }
      if (open.empty()) {
        if (groups == 1 && Norm2(normal) > 0) {
          slide_[v] = Slide::kPlane;
          axis_[v] = Normalized(normal);
        }
        continue;
      }
      if (open.size() != 2 * groups) continue;
      // On an input edge: every open neighbour on one line through v, on both sides.
      Vec3 dir = Normalized(P(open[0]) - P(v));
      bool line = Norm2(dir) > 0, before = false, after = false;
      for (uint32_t w : open) {
        const Vec3 d = P(w) - P(v);
        const double along = Dot(d, dir);
        line = line && Norm2(Cross(d, dir)) <= 1e-18 * Norm2(d);
        (along > 0 ? after : before) = true;
      }
      if (line && before && after) {
        slide_[v] = Slide::kLine;
        axis_[v] = dir;
      }
    }
  }

  // The tetrahedron sharing face `f` (the face opposite tet[f]) of t, or UINT32_MAX on the
  // boundary.
  uint32_t Neighbor(uint32_t t, int f) const {
    const Tet& tet = m_.tets[t];
    const uint32_t a = tet[(f + 1) % 4], b = tet[(f + 2) % 4], c = tet[(f + 3) % 4];
    for (uint32_t s : star_[a]) {
      if (s != t && Has(m_.tets[s], b) && Has(m_.tets[s], c)) return s;
    }
    return UINT32_MAX;
  }

  // Face f of t oriented so that the tetrahedron's inside is on its positive side.
  std::array<uint32_t, 3> InwardFace(uint32_t t, int f) const {
    const Tet& tet = m_.tets[t];
    std::array<uint32_t, 3> face = {tet[(f + 1) % 4], tet[(f + 2) % 4], tet[(f + 3) % 4]};
    if (TetVolume(P(face[0]), P(face[1]), P(face[2]), P(tet[f])) < 0) std::swap(face[0], face[1]);
    return face;
  }

  // Whether face f of cavity tetrahedron x bounds the cavity: its neighbour is outside, or
  // it is a facet's face (the cavity can reach both sides of a sheet around its rim; such
  // a face must stay, so it bounds the cavity on both sides and one side then fails to see
  // the new vertex). Facets in `opened` are the ones the new vertex splits: they do not
  // bound the cavity.
  bool OnCavityBoundary(const absl::flat_hash_set<uint32_t>& in, uint32_t x, int f,
                        const absl::flat_hash_set<FaceKey>& opened) const {
    const uint32_t y = Neighbor(x, f);
    if (y == UINT32_MAX || !in.contains(y)) return true;
    return Blocks(TetFace(m_.tets[x], f), opened);
  }
  bool Blocks(const FaceKey& face, const absl::flat_hash_set<FaceKey>& opened) const {
    return constrained_.contains(face) && !opened.contains(face);
  }

  bool InCircumsphere(const Tet& t, const Vec3& p) const {
    Vec3 cc;
    return Circumcentre(P(t[0]), P(t[1]), P(t[2]), P(t[3]), &cc) &&
           Norm2(p - cc) < Norm2(P(t[0]) - cc);
  }

  // The cavity of point p for the insertion near sliver t, and the tetrahedra that fill it
  // (each boundary face with slot 3 left for the new vertex). False when p is not inside
  // the domain on this side of the facets, or no valid cavity holds t.
  bool Cavity(uint32_t t, const Vec3& p, std::vector<uint32_t>* cavity, std::vector<Tet>* fill) {
    constexpr int kMaxWalk = 64;
    // Walk from t to the tetrahedron holding p.
    uint32_t at = t;
    for (int step = 0;; ++step) {
      if (step == kMaxWalk) return false;
      // Leave through the face p is farthest behind, but never through a facet.
      int exit = -1;
      bool behind_facet = false;
      double most = 0;
      for (int f = 0; f < 4; ++f) {
        const auto face = InwardFace(at, f);
        const double side = TetVolume(P(face[0]), P(face[1]), P(face[2]), p);
        if (side >= 0) continue;
        if (constrained_.contains(SortedFace(face[0], face[1], face[2]))) {
          behind_facet = true;
        } else if (side < most) {
          most = side;
          exit = f;
        }
      }
      if (exit < 0) {
        if (behind_facet) return false;
        break;
      }
      at = Neighbor(at, exit);
      if (at == UINT32_MAX) return false;
    }
    return GrowCavity(p, {at, t}, {}, {}, cavity, fill);
  }

  // The cavity of point p grown from the `seeds` (which it must keep: those p lies in or
  // on) and its fill, as for Cavity. The facets in `opened` (those p lies on) are split by
  // p: the cavity spans both their sides, and must keep their edges, given in `keep`, on
  // its boundary (not all the tetrahedra around one inside).
  bool GrowCavity(const Vec3& p, const std::vector<uint32_t>& seeds,
                  const absl::flat_hash_set<FaceKey>& opened,
                  const std::vector<std::pair<uint32_t, uint32_t>>& keep,
                  std::vector<uint32_t>* cavity, std::vector<Tet>* fill) {
    constexpr size_t kMaxCavity = 128;
    absl::flat_hash_set<uint32_t> in(seeds.begin(), seeds.end());
    std::vector<uint32_t> queue(seeds.begin(), seeds.end());
    while (!queue.empty() && in.size() < kMaxCavity) {
      const uint32_t x = queue.back();
      queue.pop_back();
      for (int f = 0; f < 4; ++f) {
        if (Blocks(TetFace(m_.tets[x], f), opened)) continue;
        const uint32_t y = Neighbor(x, f);
        if (y == UINT32_MAX || in.contains(y) || !InCircumsphere(m_.tets[y], p)) continue;
        in.insert(y);
        queue.push_back(y);
      }
    }
    // Make every boundary face see p, growing across it where allowed, else dropping its
    // owner; then drop tetrahedra until no vertex is inside the cavity (it would be lost).
    // A dropped tetrahedron never comes back, so this ends.
    absl::flat_hash_set<uint32_t> dropped;
    auto drop = [&](uint32_t x) {
      if (std::find(seeds.begin(), seeds.end(), x) != seeds.end()) return false;
      in.erase(x);
      dropped.insert(x);
      return true;
    };
    for (int round = 0;; ++round) {
      if (round == 64 || in.size() > kMaxCavity) return false;
      std::vector<std::pair<uint32_t, int>> hidden;
      for (uint32_t x : Sorted(in)) {
        for (int f = 0; f < 4; ++f) {
          if (!OnCavityBoundary(in, x, f, opened)) continue;
          const auto face = InwardFace(x, f);
          if (!(TetVolume(P(face[0]), P(face[1]), P(face[2]), p) > 0)) hidden.push_back({x, f});
        }
      }
      for (const auto& [x, f] : hidden) {
        if (!in.contains(x)) continue;
        const uint32_t y = Neighbor(x, f);
        if (y != UINT32_MAX && !dropped.contains(y) && !Blocks(TetFace(m_.tets[x], f), opened)) {
          in.insert(y);
        } else if (!drop(x)) {
          return false;
        }
      }
      if (!hidden.empty()) continue;
      bool inside = false;
      for (uint32_t x : Sorted(in)) {
        for (uint32_t w : m_.tets[x]) {
          if (!in.contains(x)) break;
          const bool all_in = std::all_of(star_[w].begin(), star_[w].end(),
                                          [&](uint32_t s) { return in.contains(s); });
          if (!all_in) continue;
          inside = true;
          bool any = false;
          for (uint32_t s : star_[w]) {
            if (drop(s)) {
              any = true;
              break;
            }
          }
          if (!any) return false;
        }
      }
      for (const auto& [u, w] : keep) {
        std::vector<uint32_t> around;
        for (uint32_t s : star_[u]) {
          if (Has(m_.tets[s], w)) around.push_back(s);
        }
        if (!std::all_of(around.begin(), around.end(),
                         [&](uint32_t s) { return in.contains(s); })) {
          continue;
        }
        inside = true;
        if (std::none_of(around.begin(), around.end(), drop)) return false;
      }
      if (!inside) break;
    }
    // Fill: p joined to every boundary face; every vertex of the cavity must stay on it.
    *cavity = Sorted(in);
    fill->clear();
    absl::flat_hash_set<uint32_t> on_boundary, all;
    for (uint32_t x : *cavity) {
      for (int f = 0; f < 4; ++f) {
        all.insert(m_.tets[x][f]);
        if (!OnCavityBoundary(in, x, f, opened)) continue;
        const auto face = InwardFace(x, f);
        // Inward face (f0, f1, f2) with p on its positive side: (f0, f1, f2, p) is positive.
        fill->push_back({face[0], face[1], face[2], UINT32_MAX});
        on_boundary.insert(face.begin(), face.end());
      }
    }
    return all.size() == on_boundary.size();
  }
  double Quality(const Tet& t) const {
    return MinDihedralDegrees(P(t[0]), P(t[1]), P(t[2]), P(t[3]));
  }
  // What the smoothing's second stage raises the star's sum of: the smallest dihedral
  // angle blended with the radius aspect (TetImproveOptions::radius_weight), given the
  // tetrahedron's Quality q.
  double Shape(const Tet& t, double q) const {
    if (radius_weight_ == 0) return q;
    const double ra = RadiusAspect(P(t[0]), P(t[1]), P(t[2]), P(t[3]));
    return (1 - radius_weight_) * q + radius_weight_ * kRegularDihedral * ra;
  }

  void Kill(uint32_t t) {
    dead_[t] = 1;
    for (uint32_t v : m_.tets[t]) {
      auto& s = star_[v];
      auto it = std::find(s.begin(), s.end(), t);
      *it = s.back();
      s.pop_back();
    }
    free_.push_back(t);
  }

  void Add(const Tet& tet) {
    uint32_t t;
    if (!free_.empty()) {
      t = free_.back();
      free_.pop_back();
      m_.tets[t] = tet;
      dead_[t] = 0;
      failed_[t] = 0;
      q_[t] = Quality(tet);
    } else {
      t = static_cast<uint32_t>(m_.tets.size());
      m_.tets.push_back(tet);
      dead_.push_back(0);
      failed_.push_back(0);
      q_.push_back(Quality(tet));
    }
    for (uint32_t v : tet) star_[v].push_back(t);
  }

  TetMesh& m_;
  std::vector<std::vector<uint32_t>> star_;  // vertex -> live tetrahedra
  std::vector<double> q_;                    // per tetrahedron: smallest dihedral angle
  std::vector<uint8_t> dead_;
  std::vector<uint8_t> failed_;  // per tetrahedron: insertion tried and failed, unchanged since
  std::vector<uint32_t> free_;   // dead slots to reuse
  std::vector<uint8_t> mask_;    // per vertex: bit k set = coordinate k may change
  std::vector<Slide> slide_;     // per vertex: sheet vertices that may slide
  std::vector<Vec3> axis_;       // per vertex: the plane's normal or the line's direction
  std::vector<Vec3> anchor_;     // per sliding vertex: its position before any move
  absl::flat_hash_map<FaceKey, uint32_t> constrained_;  // facets' faces -> index in m_.faces
  std::vector<std::vector<uint32_t>> sheet_faces_of_;   // vertex -> its sheet faces
  const double floor_;          // smoothing for the mean keeps every star above min(worst, floor_)
  const double radius_weight_;  // the smoothing's mean shape (Shape)
  const double split_below_;    // tetrahedra below this may split a sheet face or edge
  uint64_t facet_splits_ = 0, edge_splits_ = 0;
};

}  // namespace

absl::Status ImproveTetMesh(TetMesh* mesh, const Vec3& box_lo, const Vec3& box_hi,
                            uint32_t input_nodes, const TetImproveOptions& options,
                            TetImproveReport* report, const Progress& progress) {
  const absl::Time start = absl::Now();
  *report = {};
  Improver im(mesh, box_lo, box_hi, input_nodes, options);
  report->movable_vertices = im.movable();
  report->sliding_vertices = im.sliding();
  std::tie(report->min_dihedral_before, report->mean_dihedral_before) = im.MinMean();
  absl::Status status;
  // One flip on tetrahedron t, for its worst (mean < 0) or for the mesh's mean; counts it.
  auto flip = [&](uint32_t t, double mean) {
    const Tet tet = im.tet(t);
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        if (im.RemoveEdge(tet[a], tet[b], mean)) {
          ++report->edge_removals;
          return true;
        }
      }
    for (int f = 0; f < 4; ++f) {
      if (im.RemoveFace(t, f, mean)) {
        ++report->face_removals;
        return true;
      }
    }
    return false;
  };
  for (int pass = 0; pass < options.passes && status.ok(); ++pass) {
    uint64_t changes = 0;
    std::vector<uint32_t> bad = im.Bad(options.target_degrees);
    for (size_t i = 0; i < bad.size() && status.ok(); ++i) {
      status = progress.Tick(i, bad.size(), 4096);
      const uint32_t t = bad[i];
      if (!im.alive(t) || im.quality(t) >= options.target_degrees) continue;
      if (flip(t, -1)) {
        ++changes;
      } else if (im.quality(t) < options.insert_below_degrees && im.InsertNear(t)) {
        ++report->inserted_vertices;
        ++changes;
      }
    }
    // Then flips that raise the mean.
    const double mean = im.MinMean().second;
    bad = im.Bad(options.target_degrees);
    for (size_t i = 0; i < bad.size() && status.ok(); ++i) {
      status = progress.Tick(i, bad.size(), 4096);
      if (im.alive(bad[i]) && flip(bad[i], mean)) ++changes;
    }
    for (uint32_t v = 0; v < im.num_nodes() && status.ok(); ++v) {
      if (!im.may_move(v) || im.StarMin(v) >= options.target_degrees) continue;
      if (im.Smooth(v)) {
        ++report->smoothing_moves;
        ++changes;
      }
    }
    report->passes = pass + 1;
    if (status.ok()) status = progress.Update(static_cast<double>(pass + 1) / options.passes);
    if (changes == 0) break;
  }
  std::tie(report->min_dihedral_after, report->mean_dihedral_after) = im.MinMean();
  report->sheet_face_splits = im.facet_splits();
  report->sheet_edge_splits = im.edge_splits();
  im.Finish();
  report->seconds = absl::ToDoubleSeconds(absl::Now() - start);
  return status;
}

}  // namespace sheetmesh
