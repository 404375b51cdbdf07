// Untangles sheet triangles that cut through each other, by local moves that keep every
// triangle: a vertex of a clashing pair moved (toward the middle of its neighbours, or off
// the other triangle's plane, by at most max_move voxels), else an edge of the pair flipped.
// The surface's later steps (decimation, smoothing, wall fitting, the rim push) and the
// snapping onto the box can leave a sheet folded over itself at a vertex, or two sheets
// crossing by a fraction of a voxel; a move of that size mends it where the image cannot
// tell the difference.
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/mesh/spatial_grid.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/plc_parts.h"

namespace sheetmesh {
namespace {

constexpr double kMinMovedAngle = 1.0;  // degrees: a move may not make a sliver triangle
constexpr double kMinSplitAngle = 0.2;  // degrees: nor a split (its pieces are thin by nature)
constexpr double kMinSplitLength = 0.05;  // voxels: a split's new edges at least this long
// What neither moves, flips, splits nor patches mended at those bounds is split with thin
// pieces as a last resort: the sheets then meet in an edge where they cross, which TetGen
// can mesh (with small tetrahedra there), rather than the job being refused.
constexpr double kLastResortSplitAngle = 1e-3;
constexpr double kLastResortSplitLength = 1e-4;
constexpr int kMaxRounds = 12;
constexpr int kLastResortRounds = 8;

Triangle TriangleOf(const std::vector<Vec3>& v, const Face& f) {
  return {v[f[0]], v[f[1]], v[f[2]]};
}

class Untangler {
 public:
  Untangler(SheetTriangles& st, std::vector<Vec3>& v, const std::vector<uint8_t>& on_face,
            double max_move)
      : st_(st), v_(v), on_face_(on_face), base_move_(max_move), max_move_(max_move) {}

  UntangleStats Run() {
    UntangleStats stats;
    for (int round = 0; round < kMaxRounds + 2 + kLastResortRounds; ++round) {
      TriangleMesh mesh;
      mesh.vertices = v_;
      mesh.faces = st_.faces;
      const auto pairs = FindSelfIntersections(mesh, 100000, 1.0);
      stats.remaining_pairs = static_cast<uint32_t>(pairs.size());
      if (round == 0) stats.found_pairs = stats.remaining_pairs;
      if (pairs.empty()) break;
      Index();
      clashing_.clear();
      for (const auto& [a, b] : pairs) clashing_.insert(PairKey(a, b));
      std::vector<uint8_t> touched(st_.faces.size(), 0);
      uint32_t mended = 0;
      for (const auto& [a, b] : pairs) {
        if (touched[a] || touched[b]) continue;
        target_ = PairKey(a, b);
        if (MoveAVertex(a, b, &touched, &stats) || FlipAnEdge(a, b, &touched, &stats)) {
          ++mended;
        } else if (SplitAtCrossing(a, b, &stats) || SplitThroughCrossing(a, b, &stats)) {
          ++mended;
          break;  // the faces and their index changed: the next round looks again
        } else if (max_move_ >= 3 * base_move_ && RetriangulatePatch(a, b, &stats)) {
          ++mended;
          break;  // the faces and their index changed: the next round looks again
        }
      }
      if (mended == 0) {
        // What small moves cannot mend may need a larger one: up to three times the cap,
        // after everything else has been tried at the smaller; then thin splits.
        if (max_move_ < 3 * base_move_) {
          max_move_ += base_move_;
        } else if (min_split_angle_ > kLastResortSplitAngle) {
          min_split_angle_ = kLastResortSplitAngle;
          min_split_length_ = kLastResortSplitLength;
        } else {
          break;
        }
      }
    }
    return stats;
  }

 private:
  // The faces of each vertex, the face grid (boxes grown by what moves may add), the
  // original normals.
  void Index() {
    around_.assign(v_.size(), {});
    for (uint32_t f = 0; f < st_.faces.size(); ++f) {
      for (uint32_t u : st_.faces[f]) around_[u].push_back(f);
    }
    double edges = 0;
    for (const Face& f : st_.faces) {
      for (int k = 0; k < 3; ++k) edges += Norm(v_[f[(k + 1) % 3]] - v_[f[k]]);
    }
    const double mean = st_.faces.empty() ? 1.0 : edges / (3.0 * st_.faces.size());
    grid_ = SpatialGrid(std::max(1.0, 2.0 * mean));
    for (uint32_t f = 0; f < st_.faces.size(); ++f) {
      Vec3 lo, hi;
      TriangleBox(TriangleOf(v_, st_.faces[f]), 2 * max_move_, &lo, &hi);
      grid_.Insert(f, lo, hi);
    }
  }

  // Whether the faces in `changed` (as they are now in v_/st_) clash with any face, or a
  // face of them is a sliver or faces away from `normals` (the sheet's side there).
  bool Clean(const std::vector<uint32_t>& changed, const std::vector<Vec3>& normals,
             const std::vector<uint8_t>& gone = {}, double min_angle = kMinMovedAngle,
             const std::vector<uint32_t>& origins = {}) {
    absl::flat_hash_map<uint32_t, uint32_t> origin_of;  // changed face -> the face it was
    for (size_t i = 0; i < changed.size(); ++i) {
      origin_of[changed[i]] = origins.empty() ? changed[i] : origins[i];
    }
    for (size_t i = 0; i < changed.size(); ++i) {
      const Face& f = st_.faces[changed[i]];
      const Triangle t = TriangleOf(v_, f);
      if (MinAngleDegrees(t) < min_angle) return false;
      if (Dot(UnitNormal(t), normals[i]) <= 0) return false;
      Vec3 lo, hi;
      TriangleBox(t, 0.0, &lo, &hi);
      bool clash = false;
      const uint32_t of = origin_of[changed[i]];
      grid_.Query(lo, hi, [&](uint32_t g) {
        if (clash || g == changed[i]) return;
        const auto own = origin_of.find(g);
        if (own != origin_of.end() && g < changed[i]) return;  // that pair was looked at
        if (g < gone.size() && gone[g]) return;
        if (!FacesClash(v_, f, st_.faces[g], 1.0)) return;
        // A clash the faces they came from had already is another pair's to mend; the
        // pair being mended, or a new clash, is not allowed.
        const uint32_t og = own != origin_of.end() ? own->second : g;
        clash = PairKey(of, og) == target_ || !clashing_.contains(PairKey(of, og));
      });
      if (clash) return false;
    }
    return true;
  }

  static uint64_t PairKey(uint32_t x, uint32_t y) {
    return (uint64_t{std::min(x, y)} << 32) | std::max(x, y);
  }

  // Moves one vertex of the pair so that neither of its faces clashes with anything.
  bool MoveAVertex(uint32_t a, uint32_t b, std::vector<uint8_t>* touched, UntangleStats* stats) {
    std::vector<uint32_t> corners;
    for (uint32_t f : {a, b}) {
      for (uint32_t u : st_.faces[f]) {
        if (std::find(corners.begin(), corners.end(), u) == corners.end()) corners.push_back(u);
      }
    }
    for (uint32_t u : corners) {
      const uint8_t faces_on = on_face_[u];
      if (faces_on != 0 && (faces_on & (faces_on - 1)) != 0) continue;  // a box edge or corner
      const uint32_t other =
          std::find(st_.faces[a].begin(), st_.faces[a].end(), u) != st_.faces[a].end() ? b : a;
      const std::vector<uint32_t>& star = around_[u];
      // The sheet's side here: its star's area-weighted normal, which a face folded back
      // (a minority) turns against. After the move every face of the star must face it.
      Vec3 side_normal(0, 0, 0);
      for (uint32_t f : star) side_normal = side_normal + AreaVector(TriangleOf(v_, st_.faces[f]));
      side_normal = Normalized(side_normal);
      const std::vector<Vec3> normals(star.size(), side_normal);
      // The middle of its neighbours, and off the other triangle's plane on its own side.
      Vec3 middle(0, 0, 0);
      int n = 0;
      for (uint32_t f : star) {
        for (uint32_t w : st_.faces[f]) {
          if (w != u) middle = middle + v_[w], ++n;
        }
      }
      middle = middle * (1.0 / std::max(1, n));
      const Triangle ot = TriangleOf(v_, st_.faces[other]);
      const Vec3 on = UnitNormal(ot);
      const double side = Dot(v_[u] - ot[0], on) >= 0 ? 1.0 : -1.0;
      std::vector<Vec3> steps;
      for (double t : {0.25, 0.5, 1.0}) steps.push_back((middle - v_[u]) * t);
      for (double d : {0.25, 0.5, 1.0}) steps.push_back(on * (side * d * max_move_));
      for (double d : {0.25, 0.5, 1.0}) steps.push_back(on * (-side * d * max_move_));
      const Vec3 from = v_[u];
      for (Vec3 step : steps) {
        if (faces_on != 0) {  // stays in its box face
          for (int k = 0; k < 3; ++k) {
            if (faces_on & (3 << (2 * k))) step[k] = 0;
          }
        }
        const double len = Norm(step);
        if (len < 1e-9) continue;
        if (len > max_move_) step = step * (max_move_ / len);
        v_[u] = from + step;
        if (Clean(star, normals)) {
          for (uint32_t f : star) (*touched)[f] = 1;
          ++stats->moved_vertices;
          stats->max_move = std::max(stats->max_move, Norm(step));
          return true;
        }
      }
      v_[u] = from;
    }
    return false;
  }

  // Flips an edge of the pair shared with one other face of its piece, where that leaves
  // no clash.
  bool FlipAnEdge(uint32_t a, uint32_t b, std::vector<uint8_t>* touched, UntangleStats* stats) {
    for (uint32_t f : {a, b}) {
      for (int k = 0; k < 3; ++k) {
        const uint32_t x = st_.faces[f][k], y = st_.faces[f][(k + 1) % 3];
        const uint32_t z1 = st_.faces[f][(k + 2) % 3];
        uint32_t g = UINT32_MAX;
        int count = 0;
        for (uint32_t h : around_[x]) {
          if (h == f) continue;
          const Face& hf = st_.faces[h];
          if (std::find(hf.begin(), hf.end(), y) != hf.end()) g = h, ++count;
        }
        if (count != 1 || st_.piece[g] != st_.piece[f]) continue;
        uint32_t z2 = UINT32_MAX;
        for (uint32_t w : st_.faces[g]) {
          if (w != x && w != y) z2 = w;
        }
        if (z2 == UINT32_MAX || z2 == z1) continue;
        bool exists = false;  // the new edge may not be there already
        for (uint32_t h : around_[z1]) {
          const Face& hf = st_.faces[h];
          exists = exists || std::find(hf.begin(), hf.end(), z2) != hf.end();
        }
        if (exists) continue;
        const Face old_f = st_.faces[f], old_g = st_.faces[g];
        const Vec3 side =
            Normalized(AreaVector(TriangleOf(v_, old_f)) + AreaVector(TriangleOf(v_, old_g)));
        const std::vector<Vec3> normals = {side, side};
        st_.faces[f] = {x, z2, z1};  // x -> y -> z1 kept its turn: x, z2, z1 and y, z1, z2
        st_.faces[g] = {y, z1, z2};
        if (Clean({f, g}, normals)) {
          Reindex(f, old_f);
          Reindex(g, old_g);
          (*touched)[f] = (*touched)[g] = 1;
          ++stats->flipped_edges;
          return true;
        }
        st_.faces[f] = old_f;
        st_.faces[g] = old_g;
      }
    }
    return false;
  }

  // Two triangles that share one corner p and cross beyond it (their planes' line through p
  // runs inside both) meet along a segment p-q, q where the line leaves the first of them
  // (on its edge opposite p). Both are split there so that p-q is an edge of each: the one
  // left at q along its edge (with the triangle across that edge), the other at q along its
  // edge too, or around q where q lies inside it. They then meet in an edge, as crossing
  // sheets must in the PLC; the surface stays where it was.
  bool SplitAtCrossing(uint32_t a, uint32_t b, UntangleStats* stats) {
    const Face fa = st_.faces[a], fb = st_.faces[b];
    uint32_t p = UINT32_MAX;
    int shared = 0;
    for (uint32_t x : fa)
      for (uint32_t y : fb)
        if (x == y) p = x, ++shared;
    if (shared != 1) return false;
    auto rotate = [&](const Face& f) {  // f as (p, next, next)
      int k = 0;
      while (f[k] != p) ++k;
      return Face{f[k], f[(k + 1) % 3], f[(k + 2) % 3]};
    };
    const Face ra = rotate(fa), rb = rotate(fb);
    const Vec3 P = v_[p];
    const Vec3 na = AreaVector(TriangleOf(v_, fa)), nb = AreaVector(TriangleOf(v_, fb));
    Vec3 line = Cross(na, nb);
    if (!(Norm(line) > 1e-12 * Norm(na) * Norm(nb))) return false;  // coplanar: not here
    line = Normalized(line);
    // Where a ray from P along d leaves triangle (P, x, y) through its edge x-y: the ray's
    // parameter and the edge's, by least squares in the triangle's plane.
    auto exit = [&](const Face& f, const Vec3& d, double* t, double* u) {
      const Vec3 x = v_[f[1]], y = v_[f[2]];
      // P + t d = x + u (y - x): two unknowns, three equations.
      const Vec3 e = y - x, r = x - P;
      const double dd = Dot(d, d), de = Dot(d, e), ee = Dot(e, e), dr = Dot(d, r), er = Dot(e, r);
      const double det = dd * ee - de * de;
      if (!(std::abs(det) > 1e-12 * dd * ee)) return false;
      *t = (dr * ee - de * er) / det;
      *u = (de * dr - dd * er) / det;
      return *t > 0 && *u >= 0 && *u <= 1;
    };
    for (const Vec3& d : {line, line * -1.0}) {
      double ta, ua, tb, ub;
      if (!exit(ra, d, &ta, &ua) || !exit(rb, d, &tb, &ub)) continue;
      // The first to be left is split along its edge; the other along its edge too if it
      // is left there as well, else around q inside it.
      const bool a_first = ta <= tb;
      const Face& edge_split = a_first ? ra : rb;
      const Face& other = a_first ? rb : ra;
      const uint32_t f_edge = a_first ? a : b, f_other = a_first ? b : a;
      const double t_edge = std::min(ta, tb), t_other = std::max(ta, tb);
      const double u_edge = a_first ? ua : ub, u_other = a_first ? ub : ua;
      const Vec3 q = P + d * t_edge;
      // Too near a corner, the pieces would be slivers: a move mends that better.
      const double len = Norm(v_[edge_split[2]] - v_[edge_split[1]]);
      if (u_edge * len < min_split_length_ || (1 - u_edge) * len < min_split_length_) continue;
      // Left within a split's least length of each other (d is a unit vector), q is on the
      // other's edge too: inside it, it would make a piece with no angle.
      const bool on_other_edge =
          (t_other - t_edge) < std::max(1e-6 * (1 + t_other), min_split_length_);
      return Split(f_edge, edge_split, f_other, other, q, on_other_edge ? u_other : -1, stats);
    }
    return false;
  }

  // Two triangles sharing no corner that cut through each other meet along a segment s-e
  // whose ends lie on edges of the one or the other. Each end is added to both: on an edge
  // (with the triangle across it) where it lies on one, else inside; s-e is then an edge of
  // both triangulations (the second end lands in a piece that has the first as a corner).
  bool SplitThroughCrossing(uint32_t a, uint32_t b, UntangleStats* stats) {
    const Face fa = st_.faces[a], fb = st_.faces[b];
    for (uint32_t x : fa)
      for (uint32_t y : fb)
        if (x == y) return false;
    // Where the edges of one cross the other: the points, and which triangle's edge each is
    // on.
    struct Cut {
      Vec3 p;
      bool on_a;  // on an edge of a (inside b), else on an edge of b (inside a)
    };
    std::vector<Cut> cuts;
    auto cross = [&](const Face& edges, const Face& tri, bool on_a) {
      const Triangle t = TriangleOf(v_, tri);
      const Vec3 n = AreaVector(t);
      for (int k = 0; k < 3; ++k) {
        const Vec3 p0 = v_[edges[k]], p1 = v_[edges[(k + 1) % 3]];
        const double d0 = Dot(p0 - t[0], n), d1 = Dot(p1 - t[0], n);
        if ((d0 > 0) == (d1 > 0) || d0 == d1) continue;
        const Vec3 q = p0 + (p1 - p0) * (d0 / (d0 - d1));
        double u, w, x;
        if (!ProjectBarycentric(q, t, &u, &w, &x) || u < 0 || w < 0 || x < 0) continue;
        cuts.push_back({q, on_a});
      }
    };
    cross(fa, fb, true);
    cross(fb, fa, false);
    if (cuts.size() < 2) return false;
    // The segment: the two cuts farthest apart.
    size_t i0 = 0, i1 = 1;
    double best = -1;
    for (size_t i = 0; i < cuts.size(); ++i)
      for (size_t j = i + 1; j < cuts.size(); ++j)
        if (Norm2(cuts[i].p - cuts[j].p) > best)
          best = Norm2(cuts[i].p - cuts[j].p), i0 = i, i1 = j;
    if (best < min_split_length_ * min_split_length_) return false;  // a graze: a move mends it
    const size_t faces_before = st_.faces.size();
    const std::vector<Face> saved = st_.faces;
    const size_t vertices_before = v_.size();
    std::vector<uint32_t> changed, origin;
    const uint32_t s_id = static_cast<uint32_t>(v_.size());
    v_.push_back(cuts[i0].p);
    v_.push_back(cuts[i1].p);
    const uint32_t e_id = s_id + 1;
    bool ok = true;
    for (uint32_t tri : {a, b}) {
      // The pieces of this triangle so far (it and what splitting it adds).
      std::vector<uint32_t> pieces = {tri};
      for (uint32_t q : {s_id, e_id}) {
        if (!ok) break;
        ok = InsertPoint(q, &pieces, &changed, &origin);
      }
      if (!ok) break;
      bool joined = false;  // s-e is an edge of a piece
      for (uint32_t f : pieces) {
        const Face& pf = st_.faces[f];
        const bool has_s = std::find(pf.begin(), pf.end(), s_id) != pf.end();
        const bool has_e = std::find(pf.begin(), pf.end(), e_id) != pf.end();
        joined = joined || (has_s && has_e);
      }
      ok = joined;
    }
    if (ok) return KeepSplitOrUndo(changed, origin, saved, faces_before, vertices_before, stats);
    Undo(saved, faces_before, vertices_before);
    return false;
  }

  // Adds vertex q (already in v_) to the piece of `pieces` it lies in: on the piece's edge
  // (splitting the face across it too, which joins `pieces` when it is one of them) or
  // inside it. Records what changed. False where q lies in none.
  bool InsertPoint(uint32_t q, std::vector<uint32_t>* pieces, std::vector<uint32_t>* changed,
                   std::vector<uint32_t>* origin) {
    const Vec3& p = v_[q];
    auto record = [&](uint32_t f, uint32_t from) {
      if (std::find(changed->begin(), changed->end(), f) == changed->end()) {
        changed->push_back(f);
        origin->push_back(from);
      }
    };
    auto add = [&](uint32_t like, const Face& f) {
      const uint32_t from = OriginOf(like, *changed, *origin);
      st_.faces.push_back(f);
      st_.source.push_back(st_.source[like]);
      st_.piece.push_back(st_.piece[like]);
      st_.thickness.push_back(st_.thickness[like]);
      const uint32_t id = static_cast<uint32_t>(st_.faces.size() - 1);
      record(id, from);
      return id;
    };
    for (uint32_t f : *pieces) {
      const Face face = st_.faces[f];
      double u[3];
      if (!ProjectBarycentric(p, TriangleOf(v_, face), &u[0], &u[1], &u[2])) continue;
      const double tol = 1e-9;
      if (u[0] < -tol || u[1] < -tol || u[2] < -tol) continue;
      const uint32_t from = OriginOf(f, *changed, *origin);
      // On an edge: the corner opposite has a barycentric coordinate of (nearly) 0.
      int opposite = -1;
      for (int k = 0; k < 3; ++k) {
        if (std::abs(u[k]) <= 1e-7) opposite = k;
      }
      if (opposite < 0) {
        st_.faces[f] = {face[0], face[1], q};
        record(f, from);
        pieces->push_back(add(f, {face[1], face[2], q}));
        pieces->push_back(add(f, {face[2], face[0], q}));
        return true;
      }
      const uint32_t w = face[opposite], x = face[(opposite + 1) % 3], y = face[(opposite + 2) % 3];
      // The faces across x-y (this piece's neighbours in the sheet), split there too.
      std::vector<std::pair<uint32_t, Face>> across;
      for (uint32_t g = 0; g < st_.faces.size(); ++g) {
        if (g == f) continue;
        const Face& gf = st_.faces[g];
        for (int k = 0; k < 3; ++k) {
          const uint32_t r0 = gf[k], r1 = gf[(k + 1) % 3], r2 = gf[(k + 2) % 3];
          if ((r0 == x && r1 == y) || (r0 == y && r1 == x)) across.push_back({g, Face{r2, r0, r1}});
        }
      }
      st_.faces[f] = {w, x, q};
      record(f, from);
      pieces->push_back(add(f, {w, q, y}));
      for (const auto& [g, wxy] : across) {
        const uint32_t gfrom = OriginOf(g, *changed, *origin);
        st_.faces[g] = {wxy[0], wxy[1], q};
        record(g, gfrom);
        const uint32_t h = add(g, {wxy[0], q, wxy[2]});
        if (std::find(pieces->begin(), pieces->end(), g) != pieces->end()) pieces->push_back(h);
      }
      return true;
    }
    return false;
  }

  // The face f came from before this split began: itself, unless it was made by it.
  static uint32_t OriginOf(uint32_t f, const std::vector<uint32_t>& changed,
                           const std::vector<uint32_t>& origin) {
    for (size_t i = 0; i < changed.size(); ++i) {
      if (changed[i] == f) return origin[i];
    }
    return f;
  }

  // Keeps a split whose faces `changed` (each from the face origin[i] of `saved`, on its
  // side) leave no clash, counting it; else puts the faces and vertices back as they were.
  bool KeepSplitOrUndo(const std::vector<uint32_t>& changed, const std::vector<uint32_t>& origin,
                       const std::vector<Face>& saved, size_t faces_before, size_t vertices_before,
                       UntangleStats* stats) {
    GrowGrid(changed);
    std::vector<Vec3> normals;
    for (uint32_t from : origin) normals.push_back(UnitNormal(TriangleOf(v_, saved[from])));
    if (Clean(changed, normals, {}, min_split_angle_, origin)) {
      ++stats->split_crossings;
      if (min_split_angle_ < kMinSplitAngle) ++stats->thin_splits;
      return true;
    }
    Undo(saved, faces_before, vertices_before);
    return false;
  }

  void Undo(const std::vector<Face>& saved, size_t faces_before, size_t vertices_before) {
    st_.faces = saved;
    st_.source.resize(faces_before);
    st_.piece.resize(faces_before);
    st_.thickness.resize(faces_before);
    v_.resize(vertices_before);
  }

  // Makes the splits SplitAtCrossing chose, keeping them where they leave no clash.
  bool Split(uint32_t f_edge, const Face& edge_split, uint32_t f_other, const Face& other,
             const Vec3& q, double u_other, UntangleStats* stats) {
    const size_t faces_before = st_.faces.size();
    const std::vector<Face> saved = st_.faces;
    const uint32_t qi = static_cast<uint32_t>(v_.size());
    v_.push_back(q);
    std::vector<uint32_t> changed, origin;  // each changed face, and the face it came from
    auto add = [&](uint32_t like, const Face& f) {
      st_.faces.push_back(f);
      st_.source.push_back(st_.source[like]);
      st_.piece.push_back(st_.piece[like]);
      st_.thickness.push_back(st_.thickness[like]);
      changed.push_back(static_cast<uint32_t>(st_.faces.size() - 1));
      origin.push_back(like);
    };
    auto replace = [&](uint32_t f, const Face& with) {
      st_.faces[f] = with;
      changed.push_back(f);
      origin.push_back(f);
    };
    // Face f = (w, x, y) with x-y the edge split at q: (w, x, q) and (w, q, y).
    auto split_edge = [&](uint32_t f, const Face& wxy) {
      replace(f, {wxy[0], wxy[1], qi});
      add(f, {wxy[0], qi, wxy[2]});
    };
    // The faces across edge x-y of face f, turned so that the edge comes second and third.
    auto across = [&](uint32_t f, uint32_t x, uint32_t y) {
      std::vector<std::pair<uint32_t, Face>> out;
      for (uint32_t g : around_[x]) {
        if (g == f) continue;
        const Face& gf = st_.faces[g];
        for (int k = 0; k < 3; ++k) {
          const uint32_t r0 = gf[k], r1 = gf[(k + 1) % 3], w = gf[(k + 2) % 3];
          if ((r0 == x && r1 == y) || (r0 == y && r1 == x)) out.push_back({g, Face{w, r0, r1}});
        }
      }
      return out;
    };
    const auto neighbours_e = across(f_edge, edge_split[1], edge_split[2]);
    const auto neighbours_o = across(f_other, other[1], other[2]);
    split_edge(f_edge, edge_split);
    for (const auto& [g, wxy] : neighbours_e) {
      if (g != f_other) split_edge(g, wxy);
    }
    if (u_other >= 0) {
      split_edge(f_other, other);
      for (const auto& [g, wxy] : neighbours_o) {
        if (g != f_edge) split_edge(g, wxy);
      }
    } else {
      replace(f_other, {other[0], other[1], qi});
      add(f_other, {other[1], other[2], qi});
      add(f_other, {other[2], other[0], qi});
    }
    return KeepSplitOrUndo(changed, origin, saved, faces_before, qi, stats);
  }

  // Replaces the faces around the pair (every face of one piece at a corner of a or b) by
  // a fan from one new vertex to the patch's outline, where the outline is one loop and
  // the fan clashes with nothing: the patch's surface is kept, its tangle gone.
  bool RetriangulatePatch(uint32_t a, uint32_t b, UntangleStats* stats) {
    for (uint32_t seed : {a, b}) {
      const int32_t piece = st_.piece[seed];
      std::vector<uint32_t> patch;
      for (uint32_t f : {a, b}) {
        if (st_.piece[f] != piece) continue;
        for (uint32_t u : st_.faces[f]) {
          for (uint32_t g : around_[u]) {
            if (st_.piece[g] == piece && std::find(patch.begin(), patch.end(), g) == patch.end()) {
              patch.push_back(g);
            }
          }
        }
      }
      // The outline: directed edges of the patch that no other patch face has reversed.
      std::vector<std::pair<uint32_t, uint32_t>> outline;
      for (uint32_t f : patch) {
        for (int k = 0; k < 3; ++k) {
          const uint32_t x = st_.faces[f][k], y = st_.faces[f][(k + 1) % 3];
          int uses = 0;
          for (uint32_t g : patch) {
            const Face& gf = st_.faces[g];
            for (int j = 0; j < 3; ++j) {
              const uint32_t p = gf[j], q = gf[(j + 1) % 3];
              uses += (p == x && q == y) || (p == y && q == x);
            }
          }
          if (uses == 1) outline.emplace_back(x, y);
        }
      }
      // One simple loop, in order.
      std::vector<uint32_t> loop;
      if (outline.size() < 3) continue;
      loop.push_back(outline[0].first);
      uint32_t at = outline[0].second;
      bool simple = true;
      while (at != loop[0] && simple) {
        int next = -1, count = 0;
        for (size_t e = 0; e < outline.size(); ++e) {
          if (outline[e].first == at) next = static_cast<int>(e), ++count;
        }
        simple = count == 1 && loop.size() < outline.size();
        if (!simple) break;
        loop.push_back(at);
        at = outline[next].second;
      }
      if (!simple || loop.size() != outline.size()) continue;
      // The patch's side, thickness and place.
      Vec3 side(0, 0, 0), middle(0, 0, 0);
      double area = 0, thick = 0;
      for (uint32_t f : patch) {
        const Triangle t = TriangleOf(v_, st_.faces[f]);
        side = side + AreaVector(t);
        area += Area(t);
        thick += Area(t) * st_.thickness[f];
      }
      side = Normalized(side);
      for (uint32_t u : loop) middle = middle + v_[u];
      middle = middle * (1.0 / loop.size());
      const std::vector<Face> old_faces = [&] {
        std::vector<Face> o;
        for (uint32_t f : patch) o.push_back(st_.faces[f]);
        return o;
      }();
      const uint32_t centre = static_cast<uint32_t>(v_.size());
      v_.push_back(middle);
      std::vector<Face> fan;
      for (size_t k = 0; k < loop.size(); ++k) {
        fan.push_back({loop[k], loop[(k + 1) % loop.size()], centre});
      }
      // Patch faces first take the fan's faces; the rest of the fan is appended, the rest
      // of the patch removed at the end.
      std::vector<uint32_t> changed;
      const size_t keep = std::min(patch.size(), fan.size());
      for (size_t k = 0; k < keep; ++k) st_.faces[patch[k]] = fan[k], changed.push_back(patch[k]);
      const size_t before = st_.faces.size();
      for (size_t k = keep; k < fan.size(); ++k) {
        st_.faces.push_back(fan[k]);
        st_.source.push_back(st_.source[patch[0]]);
        st_.piece.push_back(piece);
        st_.thickness.push_back(st_.thickness[patch[0]]);
        changed.push_back(static_cast<uint32_t>(st_.faces.size() - 1));
      }
      std::vector<uint8_t> gone(st_.faces.size(), 0);
      for (size_t k = keep; k < patch.size(); ++k) gone[patch[k]] = 1;
      // A removed face must not count as a clash partner: it becomes the centre alone.
      for (size_t k = keep; k < patch.size(); ++k) st_.faces[patch[k]] = {centre, centre, centre};
      GrowGrid(changed);
      const std::vector<Vec3> normals(changed.size(), side);
      if (Clean(changed, normals, gone)) {
        for (uint32_t f : changed) st_.thickness[f] = static_cast<float>(thick / area);
        SheetTriangles kept;
        for (size_t f = 0; f < st_.faces.size(); ++f) {
          if (gone[f]) continue;
          kept.faces.push_back(st_.faces[f]);
          kept.source.push_back(st_.source[f]);
          kept.piece.push_back(st_.piece[f]);
          kept.thickness.push_back(st_.thickness[f]);
        }
        st_ = std::move(kept);
        ++stats->retriangulated_patches;
        return true;
      }
      // Undone.
      for (size_t k = 0; k < patch.size(); ++k) st_.faces[patch[k]] = old_faces[k];
      st_.faces.resize(before);
      st_.source.resize(before);
      st_.piece.resize(before);
      st_.thickness.resize(before);
      v_.pop_back();
    }
    return false;
  }

  // Puts faces added since Index() into the grid.
  void GrowGrid(const std::vector<uint32_t>& faces) {
    for (uint32_t f : faces) {
      Vec3 lo, hi;
      TriangleBox(TriangleOf(v_, st_.faces[f]), 2 * max_move_, &lo, &hi);
      grid_.Insert(f, lo, hi);
    }
  }

  // Face f changed its corners from `old`: the vertex index follows.
  void Reindex(uint32_t f, const Face& old) {
    for (uint32_t u : old) {
      auto& list = around_[u];
      list.erase(std::remove(list.begin(), list.end(), f), list.end());
    }
    for (uint32_t u : st_.faces[f]) around_[u].push_back(f);
  }

  SheetTriangles& st_;
  std::vector<Vec3>& v_;
  const std::vector<uint8_t>& on_face_;
  const double base_move_;
  double max_move_;
  std::vector<std::vector<uint32_t>> around_;
  SpatialGrid grid_{1.0};
  absl::flat_hash_set<uint64_t> clashing_;  // the round's clashing pairs, by PairKey
  uint64_t target_ = 0;                     // the pair being mended
  double min_split_angle_ = kMinSplitAngle;   // degrees, the least angle a split may make
  double min_split_length_ = kMinSplitLength;  // voxels
};

}  // namespace

UntangleStats Untangle(SheetTriangles& st, std::vector<Vec3>& v,
                       const std::vector<uint8_t>& on_face, double max_move_voxels) {
  if (st.faces.empty() || max_move_voxels <= 0) return {};
  return Untangler(st, v, on_face, max_move_voxels).Run();
}

}  // namespace sheetmesh
