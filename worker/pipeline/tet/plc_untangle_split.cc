// The untangler's splits: two sheet triangles that cross are split along their crossing so
// that they meet in an edge there, as crossing sheets must in the PLC (Untangler,
// plc_untangler.h). Each split is kept only where it leaves no clash and no piece thinner
// than the round allows.
#include <algorithm>
#include <cmath>
#include <vector>

#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/plc_untangler.h"

namespace sheetmesh::untangle_internal {

// Two triangles that share one corner p and cross beyond it (their planes' line through p
// runs inside both) meet along a segment p-q, q where the line leaves the first of them
// (on its edge opposite p). Both are split there so that p-q is an edge of each: the one
// left at q along its edge (with the triangle across that edge), the other at q along its
// edge too, or around q where q lies inside it. They then meet in an edge, as crossing
// sheets must in the PLC; the surface stays where it was.
bool Untangler::SplitAtCrossing(uint32_t a, uint32_t b, UntangleStats* stats) {
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
bool Untangler::SplitThroughCrossing(uint32_t a, uint32_t b, UntangleStats* stats) {
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
      if (Norm2(cuts[i].p - cuts[j].p) > best) best = Norm2(cuts[i].p - cuts[j].p), i0 = i, i1 = j;
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
bool Untangler::InsertPoint(uint32_t q, std::vector<uint32_t>* pieces,
                            std::vector<uint32_t>* changed, std::vector<uint32_t>* origin) {
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

// Keeps a split whose faces `changed` (each from the face origin[i] of `saved`, on its
// side) leave no clash, counting it; else puts the faces and vertices back as they were.
bool Untangler::KeepSplitOrUndo(const std::vector<uint32_t>& changed,
                                const std::vector<uint32_t>& origin, const std::vector<Face>& saved,
                                size_t faces_before, size_t vertices_before, UntangleStats* stats) {
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

void Untangler::Undo(const std::vector<Face>& saved, size_t faces_before, size_t vertices_before) {
  st_.faces = saved;
  st_.source.resize(faces_before);
  st_.piece.resize(faces_before);
  st_.thickness.resize(faces_before);
  v_.resize(vertices_before);
}

// Makes the splits SplitAtCrossing chose, keeping them where they leave no clash.
bool Untangler::Split(uint32_t f_edge, const Face& edge_split, uint32_t f_other, const Face& other,
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

}  // namespace sheetmesh::untangle_internal
