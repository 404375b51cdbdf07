#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <set>
#include <string>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/mesh/spatial_grid.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/plc_parts.h"

namespace sheetmesh {
namespace {

// Improves the sheet triangles TetGen must keep, since a thin or flat triangle forces tiny
// tetrahedra and slivers around it: an edge between two triangles of one piece that are
// nearly coplanar (normals within max_fold) is flipped where that raises the smaller of
// the two triangles' smallest angles (Lawson's rule on the sheet). A flat triangle (largest
// angle over cap_degrees) has its long edge flipped whatever the fold, and where no flip
// applies and it has an edge on the sheet's rim it is dropped, as it covers almost nothing.
// No flip touches a `frozen` vertex. Returns the number of flips and drops.
std::pair<uint32_t, uint32_t> ImproveSheetTriangles(SheetTriangles& s, const std::vector<Vec3>& v,
                                                    const std::vector<uint8_t>& on_face,
                                                    const std::vector<uint8_t>& frozen,
                                                    double max_fold, double cap_degrees) {
  uint32_t flips = 0, drops = 0;
  auto corners = [&](const Face& f) { return Triangle{v[f[0]], v[f[1]], v[f[2]]}; };
  auto key = [](uint32_t a, uint32_t b) {
    return (static_cast<uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
  };
  for (int round = 0; round < 50; ++round) {
    absl::flat_hash_map<uint64_t, std::vector<uint32_t>> edges;
    for (uint32_t f = 0; f < s.faces.size(); ++f) {
      for (int k = 0; k < 3; ++k) edges[key(s.faces[f][k], s.faces[f][(k + 1) % 3])].push_back(f);
    }
    std::vector<uint8_t> touched(s.faces.size(), 0), drop(s.faces.size(), 0);
    uint32_t changed = 0, dropped = 0;
    for (uint32_t f = 0; f < s.faces.size(); ++f) {
      if (touched[f]) continue;
      // (Plain variables, not a structured binding: the lambdas below capture them.)
      const std::pair<double, double> range = AngleRangeDegrees(corners(s.faces[f]));
      const double lo = range.first, hi = range.second;
      // The edge opposite the largest angle: the one a flip or a drop would remove.
      int longest = 0;
      double best = -1;
      for (int k = 0; k < 3; ++k) {
        const double len = Norm(v[s.faces[f][(k + 1) % 3]] - v[s.faces[f][k]]);
        if (len > best) best = len, longest = k;
      }
      const uint32_t a = s.faces[f][longest], b = s.faces[f][(longest + 1) % 3],
                     c = s.faces[f][(longest + 2) % 3];
      const std::vector<uint32_t>& across = edges.at(key(a, b));
      // A flat triangle's plane is ill-defined, so the facet it makes cuts the sheet at an
      // arbitrary angle: inside the sheet its long edge is flipped whatever the fold (its
      // obtuse vertex lies nearly on that edge, and the flip trades it and its neighbour
      // for two halves of the neighbour); on the rim, where no flip applies, it is dropped,
      // as it covers almost nothing.
      const bool flat = hi > cap_degrees;
      auto drop_it = [&] {
        drop[f] = touched[f] = 1;
        ++drops;
        ++dropped;
        ++changed;
      };
      if (flat && across.size() == 1) {
        drop_it();
        continue;
      }
      // Flips the edge a-b shared with g, the other triangle on it; false where that is not
      // allowed or not better.
      auto flip = [&]() -> bool {
        if (across.size() != 2) return false;
        const uint32_t g = across[0] == f ? across[1] : across[0];
        if (touched[g] || s.piece[f] != s.piece[g]) return false;
        // g must run b -> a (consistent orientation); d is its third vertex.
        int kb = -1;
        for (int k = 0; k < 3; ++k) {
          if (s.faces[g][k] == b && s.faces[g][(k + 1) % 3] == a) kb = k;
        }
        if (kb < 0) return false;
        const uint32_t d = s.faces[g][(kb + 2) % 3];
        if (c == d || edges.contains(key(c, d)) || frozen[a] || frozen[b] || frozen[c] || frozen[d])
          return false;
        const Face nf = {a, d, c}, ng = {d, b, c};
        const Triangle tf = corners(s.faces[f]), tg = corners(s.faces[g]), tnf = corners(nf),
                       tng = corners(ng);
        if (!flat && AngleDegrees(AreaVector(tf), AreaVector(tg)) > max_fold) return false;
        if (AngleDegrees(AreaVector(tnf), AreaVector(tng)) > max_fold) return false;
        const Vec3 up = AreaVector(tf) + AreaVector(tg);
        if (Dot(AreaVector(tnf), up) <= 0 || Dot(AreaVector(tng), up) <= 0) return false;
        const double old_min = std::min(lo, AngleRangeDegrees(tg).first);
        const double new_min = std::min(AngleRangeDegrees(tnf).first, AngleRangeDegrees(tng).first);
        if (new_min < old_min + 0.5) return false;
        const bool in_box_face =
            (on_face[a] & on_face[d] & on_face[c]) || (on_face[d] & on_face[b] & on_face[c]);
        if (in_box_face) return false;
        const double af = Area(tf), ag = Area(tg);
        const float t = static_cast<float>((s.thickness[f] * af + s.thickness[g] * ag) /
                                           std::max(af + ag, 1e-300));
        s.faces[f] = nf;
        s.faces[g] = ng;
        s.thickness[f] = s.thickness[g] = t;
        touched[f] = touched[g] = 1;
        return true;
      };
      if (flip()) {
        ++flips;
        ++changed;
      } else if (flat && (edges.at(key(b, c)).size() == 1 || edges.at(key(c, a)).size() == 1)) {
        drop_it();
      }
    }
    if (dropped > 0) s = Without(s, drop);
    if (changed == 0) break;
  }
  return {flips, drops};
}

}  // namespace

// ImproveSheetTriangles, kept only where it makes no clash: a flip moves the sheet a
// little, and where that makes it cut another sheet (near a crossing), the vertices of the
// clash are frozen and the improvement starts over. Returns the flips and drops kept.
std::vector<uint8_t> HeldAtJunctions(const SheetTriangles& s, size_t vertices) {
  absl::flat_hash_map<uint64_t, std::vector<uint32_t>> faces_on;
  for (uint32_t f = 0; f < s.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = s.faces[f][k], b = s.faces[f][(k + 1) % 3];
      faces_on[(uint64_t{std::min(a, b)} << 32) | std::max(a, b)].push_back(f);
    }
  }
  std::vector<uint8_t> held(vertices, 0);
  for (const auto& [edge, faces] : faces_on) {
    const bool junction =
        faces.size() >= 3 || (faces.size() == 2 && s.piece[faces[0]] != s.piece[faces[1]]);
    if (!junction) continue;
    for (uint32_t f : faces) {
      for (uint32_t x : s.faces[f]) held[x] = 1;
    }
  }
  return held;
}

std::pair<uint32_t, uint32_t> FlipSheetTriangles(SheetTriangles& st, const std::vector<Vec3>& v,
                                                 const std::vector<uint8_t>& on_face,
                                                 const std::vector<uint8_t>& held,
                                                 double fold_degrees, double cap_degrees) {
  std::vector<uint8_t> frozen(v.size(), 0);
  for (size_t i = 0; i < held.size() && i < frozen.size(); ++i) frozen[i] = held[i];
  for (int attempt = 0; attempt < 5; ++attempt) {
    SheetTriangles better = st;
    const auto [flips, drops] =
        ImproveSheetTriangles(better, v, on_face, frozen, fold_degrees, cap_degrees);
    if (flips == 0 && drops == 0) break;
    TriangleMesh check;
    check.vertices = v;
    check.faces = better.faces;
    const auto clash = FindSelfIntersections(check, 1000, 1.0);
    if (clash.empty()) {
      st = std::move(better);
      return {flips, drops};
    }
    for (const auto& [a, b] : clash) {
      for (uint32_t x : better.faces[a]) frozen[x] = 1;
      for (uint32_t x : better.faces[b]) frozen[x] = 1;
    }
  }
  return {0, 0};
}

// Closes the slits in the sheets: three rim edges a-b, a-c, c-b that frame no triangle,
// with c nearly on a-b (its angle over min_degrees, as for a flat triangle). The face on
// a-b is split in two at c (unless a half would be flat too), so the rim runs a-c-b on both sides
// and the slit is gone. Left open, TetGen must fill the slit, flat as it is, with a sliver, and any
// point the improvement puts beside it lands a fraction of a voxel from c. Where a round's splits
// would make a clash, none of them is made. Returns the number of slits closed.
uint32_t CloseSlits(SheetTriangles& s, const std::vector<Vec3>& v, double min_degrees) {
  const double max_cos = std::cos(min_degrees * std::numbers::pi / 180.0);
  uint32_t closed = 0;
  for (int round = 0; round < 5; ++round) {
    TriangleMesh faces_only;
    faces_only.faces = s.faces;
    const EdgeIndex edges(faces_only);
    absl::flat_hash_map<uint32_t, std::vector<uint32_t>> rim;  // vertex -> rim neighbours
    for (const EdgeIndex::Edge& e : edges.edges()) {
      if (e.count != 1) continue;
      rim[e.a].push_back(e.b);
      rim[e.b].push_back(e.a);
    }
    SheetTriangles out = s;
    std::vector<uint8_t> split(s.faces.size(), 0);
    uint32_t count = 0;
    for (const EdgeIndex::Edge& e : edges.edges()) {
      if (e.count != 1) continue;
      const uint32_t f = edges.faces(e)[0];
      if (split[f]) continue;
      const Face face = s.faces[f];
      const auto& ra = rim[e.a];
      for (uint32_t c : rim[e.b]) {
        if (c == face[0] || c == face[1] || c == face[2]) continue;
        if (std::find(ra.begin(), ra.end(), c) == ra.end()) continue;
        const Vec3 ca = v[e.a] - v[c], cb = v[e.b] - v[c];
        const double la = Norm(ca), lb = Norm(cb);
        if (!(la > 0 && lb > 0) || !(Dot(ca, cb) < max_cos * la * lb)) continue;
        // Face (a, b, x) in its own order becomes (a, c, x) and (c, b, x).
        const int k = face[0] == e.a ? 0 : face[1] == e.a ? 1 : 2;
        const bool forward = face[(k + 1) % 3] == e.b;
        Face first = face, second = face;
        first[forward ? (k + 1) % 3 : (k + 2) % 3] = c;  // b -> c
        second[k] = c;                                   // a -> c
        // Neither half may be flat itself (c nearly on F's other edges too: F is a sliver).
        auto flat = [&](const Face& t) {
          return AngleRangeDegrees({v[t[0]], v[t[1]], v[t[2]]}).second > min_degrees;
        };
        if (flat(first) || flat(second)) continue;
        out.faces[f] = first;
        out.faces.push_back(second);
        out.source.push_back(s.source[f]);
        out.piece.push_back(s.piece[f]);
        out.thickness.push_back(s.thickness[f]);
        split[f] = 1;
        ++count;
        break;
      }
    }
    if (count == 0) break;
    TriangleMesh check;
    check.vertices = v;
    check.faces = out.faces;
    if (!FindSelfIntersections(check, 1, 1.0).empty()) break;
    s = std::move(out);
    closed += count;
  }
  return closed;
}

// Drops sheet triangles that lie on another sheet. Where part of one triangle comes within
// `gap` of another's interior while their planes are within max_degrees of parallel (they
// run alongside, not into each other), TetGen must fill the thin wedge between them with
// tetrahedra as thin as the gap, slivers that nothing after can mend. Of such a pair the
// one with more rim edges goes (ties: the smaller), if it has a rim edge at all: a fragment
// lying on a sheet, or a sheet's rim running over another sheet. Two interior triangles
// are left as they are, as dropping one would open a hole. Returns the number dropped.
uint32_t DropOverlaps(SheetTriangles& s, const std::vector<Vec3>& v,
                      const std::vector<uint8_t>& on_face, const std::vector<uint8_t>& held,
                      double gap, double max_degrees) {
  constexpr int kSamples = 6;  // points per edge of the barycentric grid sampled
  const double max_sin = std::sin(max_degrees * std::numbers::pi / 180.0);
  auto corners = [&](uint32_t f) {
    return Triangle{v[s.faces[f][0]], v[s.faces[f][1]], v[s.faces[f][2]]};
  };
  // Whether some point of b lies within gap of a's plane and projects inside a (beyond
  // the vertices they share).
  auto near_interior = [&](uint32_t fa, uint32_t fb) {
    const Triangle a = corners(fa), b = corners(fb);
    const Vec3 n = AreaVector(a);
    const double n2 = Norm2(n);
    for (int i = 0; i <= kSamples; ++i)
      for (int j = 0; i + j <= kSamples; ++j) {
        const double u = static_cast<double>(i) / kSamples, w = static_cast<double>(j) / kSamples;
        const Vec3 p = b[0] + (b[1] - b[0]) * u + (b[2] - b[0]) * w;
        if (std::any_of(a.begin(), a.end(), [&](const Vec3& q) { return Norm2(p - q) < 1e-18; }))
          continue;
        // Barycentric coordinates of p's projection: signed areas against a's normal.
        const double l0 = Dot(Cross(a[1] - p, a[2] - p), n) / n2,
                     l1 = Dot(Cross(a[2] - p, a[0] - p), n) / n2, l2 = 1 - l0 - l1;
        if (l0 <= 1e-6 || l1 <= 1e-6 || l2 <= 1e-6) continue;
        if (std::abs(Dot(p - a[0], n)) < gap * std::sqrt(n2)) return true;
      }
    return false;
  };
  uint32_t dropped = 0;
  for (int round = 0; round < 20; ++round) {
    const size_t n = s.faces.size();
    // Rim edges per triangle (edges of one triangle only), areas, and bounding boxes grown
    // by the gap.
    std::vector<int> rim(n, 0);
    TriangleMesh faces_only;
    faces_only.faces = s.faces;
    const EdgeIndex edges(faces_only);
    for (const EdgeIndex::Edge& e : edges.edges()) {
      if (e.count == 1 && (on_face[e.a] & on_face[e.b]) == 0) ++rim[edges.faces(e)[0]];
    }
    std::vector<double> area(n);
    std::vector<Vec3> lo(n), hi(n);
    std::vector<uint32_t> order(n);
    for (uint32_t f = 0; f < n; ++f) {
      const Triangle t = corners(f);
      area[f] = Area(t);
      TriangleBox(t, gap, &lo[f], &hi[f]);
      order[f] = f;
    }
    // Sweep along x; pairs whose grown boxes meet on all three axes are tested.
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
      return lo[a].x < lo[b].x || (lo[a].x == lo[b].x && a < b);
    });
    std::vector<uint8_t> drop(n, 0);
    uint32_t count = 0;
    for (size_t i = 0; i < n; ++i) {
      const uint32_t a = order[i];
      for (size_t j = i + 1; j < n && lo[order[j]].x <= hi[a].x; ++j) {
        const uint32_t b = order[j];
        if (drop[a] || drop[b]) continue;
        if (lo[b].y > hi[a].y || lo[a].y > hi[b].y || lo[b].z > hi[a].z || lo[a].z > hi[b].z)
          continue;
        // An edge shared (a fold there is the flips' business) or planes at an angle: no
        // overlap.
        int shared = 0;
        for (uint32_t x : s.faces[a])
          shared += x == s.faces[b][0] || x == s.faces[b][1] || x == s.faces[b][2];
        if (shared >= 2) continue;
        bool at_junction = false;
        for (uint32_t x : s.faces[a]) {
          at_junction |=
              held[x] && (x == s.faces[b][0] || x == s.faces[b][1] || x == s.faces[b][2]);
        }
        if (at_junction) continue;
        const Vec3 na = AreaVector(corners(a)), nb = AreaVector(corners(b));
        if (Norm(Cross(na, nb)) > max_sin * Norm(na) * Norm(nb)) continue;
        if (!near_interior(a, b) && !near_interior(b, a)) continue;
        const uint32_t loser =
            rim[a] != rim[b] ? (rim[a] > rim[b] ? a : b) : (area[a] <= area[b] ? a : b);
        if (rim[loser] == 0) continue;
        drop[loser] = 1;
        ++count;
      }
    }
    if (count == 0) break;
    s = Without(s, drop);
    dropped += count;
  }
  return dropped;
}

// Opens the narrow wedges between a sheet face and a sheet edge that leaves one of its
// corners just off its plane, over the face (the edge's direction, projected onto the
// plane, lies inside the face's angle at that corner). TetGen must fill such a wedge with
// tetrahedra whose dihedral angle there is about as small as the wedge, and nothing
// after can mend them without splitting the face many times over. The edge's far end
// moves straight away from the face's plane until the edge stands min_degrees off it, by
// at most max_move in all, and only where that opens the narrowest wedge around it and
// its neighbours; vertices on the box stay. So does the third corner of a face that meets
// a box face along an edge at under min_degrees, straight off the box face. A move that
// makes triangles clash is undone.
// Returns the number of vertices moved.
uint32_t OpenWedges(const SheetTriangles& st, const std::vector<uint8_t>& on_face,
                    double min_degrees, double max_move, std::vector<Vec3>& v) {
  if (!(min_degrees > 0) || !(max_move > 0) || st.faces.empty()) return 0;
  const double sin_min = std::sin(min_degrees * std::numbers::pi / 180.0);
  const double tan_min = std::tan(min_degrees * std::numbers::pi / 180.0);
  std::vector<std::vector<uint32_t>> faces_of(v.size());
  std::vector<std::vector<uint32_t>> next(v.size());
  for (uint32_t f = 0; f < st.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = st.faces[f][k];
      faces_of[a].push_back(f);
      for (int j = 1; j < 3; ++j) next[a].push_back(st.faces[f][(k + j) % 3]);
    }
  }
  for (auto& n : next) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  struct Wedge {
    double sine = 2;    // of the edge's angle to the face's plane
    uint32_t far = 0;   // the edge's far end
    double height = 0;  // of the far end over the face's plane (signed), and
    double length = 0;  // the edge's length
    Vec3 normal;        // the face's unit normal
  };
  // The narrowest wedge at corner u (sine 2: none).
  auto narrowest = [&](uint32_t u) {
    Wedge best;
    for (uint32_t f : faces_of[u]) {
      const Face& t = st.faces[f];
      const int k = t[0] == u ? 0 : t[1] == u ? 1 : 2;
      const Vec3 e1 = v[t[(k + 1) % 3]] - v[u], e2 = v[t[(k + 2) % 3]] - v[u];
      const Vec3 n = Cross(e1, e2);
      const double n2 = Norm2(n);
      if (!(n2 > 0)) continue;
      const Vec3 unit = n / std::sqrt(n2);
      for (uint32_t x : next[u]) {
        if (x == t[0] || x == t[1] || x == t[2]) continue;
        const Vec3 d = v[x] - v[u];
        const double len = Norm(d);
        if (!(len > 0)) continue;
        const double h = Dot(d, unit);
        // Inside the angle: d's projection is a positive combination of e1 and e2.
        if (!(Dot(Cross(e1, d), n) > 0 && Dot(Cross(d, e2), n) > 0)) continue;
        const double sine = std::abs(h) / len;
        if (sine < best.sine) best = {sine, x, h, len, unit};
      }
    }
    return best;
  };
  auto around = [&](uint32_t w) {
    double m = narrowest(w).sine;
    for (uint32_t x : next[w]) m = std::min(m, narrowest(x).sine);
    return m;
  };
  const std::vector<Vec3> original = v;
  std::vector<uint8_t> moved(v.size(), 0);
  for (int round = 0; round < 3; ++round) {
    bool any = false;
    for (uint32_t u = 0; u < v.size(); ++u) {
      if (faces_of[u].empty()) continue;
      const Wedge w = narrowest(u);
      if (!(w.sine < sin_min) || on_face[w.far] != 0) continue;
      const double before = around(w.far);
      // Moving along the normal keeps the edge's length in the plane.
      const double in_plane = std::sqrt(std::max(0.0, w.length * w.length - w.height * w.height));
      const double need = in_plane * tan_min - std::abs(w.height);
      const Vec3 start = v[w.far];
      Vec3 to = start + w.normal * ((w.height < 0 ? -1.0 : 1.0) * need);
      // At most max_move from where the vertex began.
      const Vec3 off = to - original[w.far];
      if (Norm(off) > max_move) to = original[w.far] + off * (max_move / Norm(off));
      v[w.far] = to;
      if (around(w.far) > before + 1e-9) {
        moved[w.far] = 1;
        any = true;
      } else {
        v[w.far] = start;
      }
    }
    if (!any) break;
  }
  // A sheet face with an edge on a box face meets that face at its own angle: where that is
  // under min_degrees (a sheet grazing the box), its third corner moves straight off the
  // box face until it is min_degrees, as for an edge over a face, unless that narrows the
  // wedges around it.
  for (int round = 0; round < 3; ++round) {
    bool any = false;
    for (const Face& t : st.faces) {
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = t[k], b = t[(k + 1) % 3], o = t[(k + 2) % 3];
        const uint8_t shared = on_face[a] & on_face[b];
        if (shared == 0 || on_face[o] != 0) continue;
        for (int face = 0; face < 6; ++face) {
          if (!(shared & (1 << face))) continue;
          const int axis = Axis(face);
          const double inward = Low(face) ? 1.0 : -1.0;
          const Vec3 e = Normalized(v[b] - v[a]);
          const Vec3 s = v[o] - v[a];
          const double h = (v[o][axis] - v[a][axis]) * inward;  // > 0: inside the box
          const Vec3 across = s - e * Dot(s, e);
          const double in_plane = std::sqrt(std::max(0.0, Norm2(across) - h * h));
          if (!(h > 0) || !(h < in_plane * tan_min)) continue;
          const double before = around(o);
          const Vec3 start = v[o];
          Vec3 to = start;
          to[axis] += inward * (in_plane * tan_min - h);
          const Vec3 off = to - original[o];
          if (Norm(off) > max_move) to = original[o] + off * (max_move / Norm(off));
          v[o] = to;
          if (around(o) < std::min(before, sin_min) - 1e-12) {
            v[o] = start;
            continue;
          }
          moved[o] = 1;
          any = true;
        }
      }
    }
    if (!any) break;
  }
  // Undo the moves of vertices in clashing triangles, until none clash.
  for (int round = 0; round < 8; ++round) {
    TriangleMesh check;
    check.vertices = v;
    check.faces = st.faces;
    const auto clash = FindSelfIntersections(check, 1000, 1.0);
    if (clash.empty()) break;
    bool undone = false;
    for (const auto& [a, b] : clash) {
      for (const uint32_t f : {a, b}) {
        for (uint32_t x : st.faces[f]) {
          if (!moved[x]) continue;
          v[x] = original[x];
          moved[x] = 0;
          undone = true;
        }
      }
    }
    if (!undone) break;
  }
  return static_cast<uint32_t>(std::count(moved.begin(), moved.end(), 1));
}

absl::Status ResolveClashes(const std::vector<Vec3>& v, bool checked_clean,
                            const std::vector<int32_t>& body_pieces, const Placement& placement,
                            const PlcOptions& options, SheetTriangles* st, PlcStats* stats,
                            std::vector<Clash>* clashes) {
  if (checked_clean) return absl::OkStatus();
  TriangleMesh kept;
  kept.faces = st->faces;
  kept.vertices = v;
  const std::vector<uint32_t>& source = st->source;
  const std::vector<std::pair<uint32_t, uint32_t>> pairs = FindSelfIntersections(kept, 10000, 1.0);
  if (pairs.empty()) return absl::OkStatus();
  if (clashes != nullptr) {
    for (const auto& [a, b] : pairs) {
      Clash c{source[a], source[b], Corners(kept, a), Corners(kept, b)};
      for (Vec3& p : c.ta) p = placement.ToPhysical(p);
      for (Vec3& p : c.tb) p = placement.ToPhysical(p);
      clashes->push_back(c);
    }
  }
  if (!options.repair) {
    std::string list;
    for (size_t i = 0; i < pairs.size() && i < 5; ++i) {
      const auto [a, b] = pairs[i];
      const Triangle ta = Corners(kept, a), tb = Corners(kept, b);
      auto fmt = [&](const Triangle& t) {
        std::string s;
        for (const Vec3& p0 : t) {
          const Vec3 p = placement.ToPhysical(p0);
          absl::StrAppendFormat(&s, "(%.4g,%.4g,%.4g)", p.x, p.y, p.z);
        }
        return s;
      };
      absl::StrAppendFormat(&list, "; triangles %d %s and %d %s", source[a], fmt(ta), source[b],
                            fmt(tb));
    }
    return absl::FailedPreconditionError(absl::StrCat(
        pairs.size(), " pairs of sheet triangles intersect", list, pairs.size() > 5 ? "; ..." : "",
        " (plc.repair removes the smaller of each pair)"));
  }
  // Repair, the last resort after untangling: drop the smaller triangle of each clashing
  // pair, again while any clash is left (a tangle of several can need more than one round;
  // the rounds end, since each removes a triangle). A body's wall is spared where it clashes
  // with a sheet: without it the body's region leaks into the rock, a sheet only gets a hole.
  auto is_body = [&](uint32_t f) {
    return std::binary_search(body_pieces.begin(), body_pieces.end(), st->piece[f]);
  };
  const size_t before = st->faces.size();
  std::vector<std::pair<uint32_t, uint32_t>> left = pairs;
  while (!left.empty()) {
    std::vector<uint8_t> drop(kept.faces.size(), 0);
    for (const auto& [a, b] : left) {
      if (drop[a] || drop[b]) continue;
      const double area_a = Area(Corners(kept, a)), area_b = Area(Corners(kept, b));
      const bool body_a = is_body(a), body_b = is_body(b);
      const uint32_t loser = body_a != body_b ? (body_a ? b : a) : (area_a < area_b ? a : b);
      drop[loser] = 1;
      stats->repaired_area_voxels += loser == a ? area_a : area_b;
    }
    *st = Without(*st, drop);
    kept.faces = st->faces;
    left = FindSelfIntersections(kept, 10000, 1.0);
  }
  stats->repaired_triangles = static_cast<uint32_t>(before - st->faces.size());
  return absl::OkStatus();
}

}  // namespace sheetmesh
