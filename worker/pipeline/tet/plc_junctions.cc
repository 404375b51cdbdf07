// Junction lines straightened (issue 64, junctions as curves; issue 65, conditioning what
// reaches TetGen). Where sheets meet, the dual surface's junction line — the chain of edges
// that three or more sheet triangles share — zig-zags from one cell to the next, and the
// triangle spanning two consecutive links of the chain lies in neither sheet: it folds onto
// one of them at a degree or two (the 192^3 phantom at r = 4: 1.06°, its four sheets
// crossing at 45–82°), and no conforming mesh has a better angle there. A vertex u of such
// a chain between a and c moves onto the segment a-c: the triangle (a, u, c) collapses and
// goes, the faces on edge a-c are split at u, and the sheets then meet on a straight line
// at the angle their faces give.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/plc_parts.h"

namespace sheetmesh {
namespace {

constexpr double kDegrees = 180.0 / std::numbers::pi;
// A chain bending more sharply than this at u is a corner of the junction, not a zig-zag.
constexpr double kLeastChainAngleDegrees = 100.0;
// The foot of u on a-c lies this far inside the segment (a fraction of its length), or u
// stays: a vertex beyond a neighbour is no link between them.
constexpr double kInsideSegment = 0.05;

// One straightening: u onto `to` on segment a-c; `drop` the faces holding a, u and c, and
// `split` the others on edge a-c.
struct Straightening {
  uint32_t u = 0, a = 0, c = 0;
  Vec3 to;
  std::vector<uint32_t> drop, split;
};

// The wedges between faces at some edges: the narrowest (degrees; 360: none), and how far
// those under an aim fall short of it in all.
struct Wedges {
  double narrowest = 360;
  double deficit = 0;
  void Add(double gap, double aim) {
    narrowest = std::min(narrowest, gap);
    if (gap < aim) deficit += aim - gap;
  }
  // Wider at the narrowest, or as wide there and less short of the aim elsewhere.
  bool Better(const Wedges& than) const {
    return narrowest > than.narrowest + 1e-6 ||
           (narrowest >= than.narrowest - 1e-9 && deficit < than.deficit - 1e-6);
  }
};

// The wedges between the faces around an edge a-b, degrees, into `out`. A face whose far
// corner lies on the edge's line has no side and counts for nothing.
void WedgesAround(uint32_t a, uint32_t b, const std::vector<Face>& faces,
                  const std::vector<Vec3>& v, double aim, Wedges* out) {
  const Vec3 e = Normalized(v[b] - v[a]);
  std::vector<Vec3> sides;
  for (const Face& t : faces) {
    const Vec3 s = v[Opposite(t, a, b)] - v[a];
    const Vec3 across = s - e * Dot(s, e);
    const double len = Norm(across);
    if (!(len > 1e-9 * std::max(1.0, Norm(s)))) continue;
    sides.push_back(across / len);
  }
  for (const EdgeWedge& w : WedgesAroundEdge(e, sides)) out->Add(w.degrees, aim);
}

// The narrowest wedge between faces on the edge a-b, degrees (360: fewer than two).
double NarrowestAround(uint32_t a, uint32_t b, const std::vector<Face>& faces,
                       const std::vector<Vec3>& v) {
  Wedges w;
  WedgesAround(a, b, faces, v, 0, &w);
  return w.narrowest;
}

// The wedges between faces at the edges of `around` (the faces whose shape a change alters,
// before or after it), the faces on each edge being those of `edge_faces` less `gone`,
// plus `added`.
Wedges WedgesAt(const std::vector<Face>& around, const std::vector<Face>& added,
                const std::vector<uint32_t>& gone, const SheetTriangles& st,
                const absl::flat_hash_map<uint64_t, std::vector<uint32_t>>& edge_faces,
                const std::vector<Vec3>& v, double aim) {
  Wedges out;
  std::vector<uint64_t> edges;
  for (const Face& t : around) {
    for (int k = 0; k < 3; ++k) edges.push_back(EdgeKey(t[k], t[(k + 1) % 3]));
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  for (const uint64_t key : edges) {
    const uint32_t a = static_cast<uint32_t>(key >> 32), b = static_cast<uint32_t>(key);
    std::vector<Face> faces;
    if (const auto it = edge_faces.find(key); it != edge_faces.end()) {
      for (uint32_t f : it->second) {
        if (std::find(gone.begin(), gone.end(), f) == gone.end()) faces.push_back(st.faces[f]);
      }
    }
    for (const Face& t : added) {
      const bool has_a = t[0] == a || t[1] == a || t[2] == a;
      const bool has_b = t[0] == b || t[1] == b || t[2] == b;
      if (has_a && has_b) faces.push_back(t);
    }
    WedgesAround(a, b, faces, v, aim, &out);
  }
  return out;
}

bool Holds(const Face& t, uint32_t x) { return t[0] == x || t[1] == x || t[2] == x; }

}  // namespace

uint32_t StraightenJunctions(SheetTriangles& st, std::vector<Vec3>& v,
                             const std::vector<uint8_t>& on_face, double min_degrees,
                             double max_move) {
  if (!(min_degrees > 0) || !(max_move > 0) || st.faces.empty()) return 0;
  const double least_cos = std::cos(kLeastChainAngleDegrees / kDegrees);
  uint32_t straightened = 0;
  std::vector<uint8_t> done(v.size(), 0);
  for (int round = 0; round < 4; ++round) {
    const SheetIndex index = IndexSheets(st, v, 0.0);
    // Each vertex's neighbours along junction lines.
    std::vector<std::vector<uint32_t>> along(v.size());
    for (const auto& [key, faces] : index.edge_faces) {
      if (faces.size() < 3) continue;
      const uint32_t a = static_cast<uint32_t>(key >> 32), b = static_cast<uint32_t>(key);
      along[a].push_back(b);
      along[b].push_back(a);
    }
    // Every candidate's move, with the narrowest wedge around it before and after.
    struct Option {
      Straightening s;
      std::vector<uint32_t> touched;  // the faces whose shape it alters
      Wedges after;
    };
    std::vector<Option> options;
    for (uint32_t u = 0; u < v.size(); ++u) {
      if (along[u].size() != 2 || on_face[u] != 0 || done[u]) continue;
      const uint32_t a = along[u][0], c = along[u][1];
      const Vec3 ua = v[a] - v[u], uc = v[c] - v[u], ac = v[c] - v[a];
      if (!(Dot(ua, uc) < least_cos * Norm(ua) * Norm(uc))) continue;
      const double t = Dot(v[u] - v[a], ac) / Norm2(ac);
      if (!(t > kInsideSegment && t < 1 - kInsideSegment)) continue;
      Option o{{u, a, c, v[a] + ac * t, {}, {}}, index.faces_of[u], {}};
      Straightening& s = o.s;
      if (!(Norm(s.to - v[u]) <= max_move)) continue;
      if (const auto it = index.edge_faces.find(EdgeKey(a, c)); it != index.edge_faces.end()) {
        for (uint32_t f : it->second) (Holds(st.faces[f], u) ? s.drop : s.split).push_back(f);
      }
      o.touched.insert(o.touched.end(), s.split.begin(), s.split.end());
      std::vector<Face> old_faces;
      for (uint32_t f : o.touched) old_faces.push_back(st.faces[f]);
      const Wedges was = WedgesAt(old_faces, {}, {}, st, index.edge_faces, v, min_degrees);
      if (!(was.narrowest < min_degrees)) continue;
      // After: u's faces but those dropped, and the split ones' halves in their place.
      std::vector<Face> new_faces, halves;
      for (uint32_t f : index.faces_of[u]) {
        if (std::find(s.drop.begin(), s.drop.end(), f) == s.drop.end()) {
          new_faces.push_back(st.faces[f]);
        }
      }
      for (uint32_t f : s.split) {
        for (const Face& half : HalvesAt(st.faces[f], a, c, u)) halves.push_back(half);
      }
      new_faces.insert(new_faces.end(), halves.begin(), halves.end());
      std::vector<uint32_t> gone = s.drop;
      gone.insert(gone.end(), s.split.begin(), s.split.end());
      const Vec3 start = v[u];
      v[u] = s.to;
      o.after = WedgesAt(new_faces, halves, gone, st, index.edge_faces, v, min_degrees);
      v[u] = start;
      if (o.after.Better(was)) options.push_back(std::move(o));
    }
    // The widest wedge after first (a neighbour of the zig-zag's vertex may widen it a
    // little by moving too); changes of a round touch no face in common.
    std::sort(options.begin(), options.end(), [](const Option& x, const Option& y) {
      return x.after.narrowest > y.after.narrowest ||
             (x.after.narrowest == y.after.narrowest && x.s.u < y.s.u);
    });
    std::vector<Straightening> changes;
    std::vector<uint8_t> busy(v.size(), 0);
    for (Option& o : options) {
      bool free = true;
      for (uint32_t f : o.touched) {
        for (uint32_t x : st.faces[f]) free = free && !busy[x];
      }
      if (!free) continue;
      for (uint32_t f : o.touched) {
        for (uint32_t x : st.faces[f]) busy[x] = 1;
      }
      changes.push_back(std::move(o.s));
    }
    if (changes.empty()) break;
    std::vector<size_t> left_out;
    const uint32_t made = ApplyLeavingClashesOut(
        changes.size(),
        [&](const std::vector<size_t>& kept, SheetTriangles& out, std::vector<Vec3>& moved,
            std::vector<int>& owner) {
          owner.assign(out.faces.size(), -1);
          std::vector<uint8_t> drop(out.faces.size(), 0);
          for (size_t i : kept) {
            const Straightening& s = changes[i];
            const int by = static_cast<int>(i);
            moved[s.u] = s.to;
            for (uint32_t f : index.faces_of[s.u]) owner[f] = by;
            for (uint32_t f : s.drop) drop[f] = 1;
            SplitEdgeFaces(s.a, s.c, s.u, s.split, by, out, owner);
          }
          drop.resize(out.faces.size(), 0);
          std::vector<int> kept_owner;
          for (size_t f = 0; f < out.faces.size(); ++f) {
            if (!drop[f]) kept_owner.push_back(owner[f]);
          }
          out = Without(out, drop);
          owner = std::move(kept_owner);
        },
        st, v, &left_out);
    for (const Straightening& s : changes) done[s.u] = 1;
    straightened += made;
    if (made == 0) break;
  }
  return straightened;
}

uint32_t OpenDihedralWedges(SheetTriangles& st, std::vector<Vec3>& v,
                            const std::vector<uint8_t>& on_face, double min_degrees,
                            double max_move) {
  if (!(min_degrees > 0) || !(max_move > 0) || st.faces.empty()) return 0;
  const std::vector<Vec3> original = v;
  uint32_t opened = 0;
  std::vector<uint8_t> moved(v.size(), 0);
  for (int round = 0; round < 4; ++round) {
    const SheetIndex index = IndexSheets(st, v, 0.0);
    struct Move {
      uint32_t x;
      Vec3 to;
    };
    std::vector<Move> moves;
    std::vector<uint8_t> busy(v.size(), 0);
    // The narrowest wedge in the faces around vertex x.
    auto around = [&](uint32_t x) {
      std::vector<Face> faces;
      for (uint32_t f : index.faces_of[x]) faces.push_back(st.faces[f]);
      return WedgesAt(faces, {}, {}, st, index.edge_faces, v, min_degrees);
    };
    struct Narrow {
      double gap;
      uint64_t key;
    };
    std::vector<Narrow> narrow;
    for (const auto& [key, faces] : index.edge_faces) {
      if (faces.size() < 2) continue;
      const uint32_t a = static_cast<uint32_t>(key >> 32), b = static_cast<uint32_t>(key);
      std::vector<Face> on_edge;
      for (uint32_t f : faces) on_edge.push_back(st.faces[f]);
      const double gap = NarrowestAround(a, b, on_edge, v);
      if (gap < min_degrees) narrow.push_back({gap, key});
    }
    std::sort(narrow.begin(), narrow.end(), [](const Narrow& x, const Narrow& y) {
      return x.gap < y.gap || (x.gap == y.gap && x.key < y.key);
    });
    for (const auto& [gap, key] : narrow) {
      const uint32_t a = static_cast<uint32_t>(key >> 32), b = static_cast<uint32_t>(key);
      const Vec3 e = Normalized(v[b] - v[a]);
      // The far corners of the faces on the edge, with their sides' directions.
      std::vector<uint32_t> far;
      for (uint32_t f : index.edge_faces.at(key)) far.push_back(Opposite(st.faces[f], a, b));
      auto side = [&](const Vec3& p) {
        const Vec3 s = p - v[a];
        const Vec3 across = s - e * Dot(s, e);
        return across / std::max(Norm(across), 1e-300);
      };
      // The two far corners whose sides make the narrowest gap.
      uint32_t c = UINT32_MAX, d = UINT32_MAX;
      double best = 4;
      for (size_t i = 0; i < far.size(); ++i) {
        for (size_t j = i + 1; j < far.size(); ++j) {
          if (far[i] == far[j]) continue;
          const double angle =
              std::acos(std::clamp(Dot(side(v[far[i]]), side(v[far[j]])), -1.0, 1.0));
          if (angle < best) best = angle, c = far[i], d = far[j];
        }
      }
      if (c == UINT32_MAX) continue;
      const double need = min_degrees / kDegrees - best;
      if (!(need > 0)) continue;
      // Turn x about the edge's line away from the other's side by phi.
      auto turned = [&](uint32_t x, uint32_t other, double phi) {
        const Vec3 r = v[x] - v[a];
        const Vec3 along = e * Dot(r, e), perp = r - along;
        const Vec3 plus = v[a] + along + perp * std::cos(phi) + Cross(e, perp) * std::sin(phi);
        const Vec3 minus = v[a] + along + perp * std::cos(phi) - Cross(e, perp) * std::sin(phi);
        return Dot(side(plus), side(v[other])) < Dot(side(minus), side(v[other])) ? plus : minus;
      };
      Move chosen{UINT32_MAX, {}};
      Wedges chosen_after;
      chosen_after.narrowest = -1;
      for (const auto& [x, other] : {std::pair{c, d}, std::pair{d, c}}) {
        if (on_face[x] != 0 || busy[x]) continue;
        const Vec3 to = turned(x, other, need);
        if (!(Norm(to - original[x]) <= max_move)) continue;
        const Wedges before = around(x);
        const Vec3 start = v[x];
        v[x] = to;
        const Wedges after = around(x);
        v[x] = start;
        if (after.Better(before) && after.Better(chosen_after)) {
          chosen = {x, to}, chosen_after = after;
        }
      }
      if (chosen.x == UINT32_MAX) continue;
      bool free = true;
      for (uint32_t f : index.faces_of[chosen.x]) {
        for (uint32_t y : st.faces[f]) free = free && !busy[y];
      }
      if (!free) continue;
      for (uint32_t f : index.faces_of[chosen.x]) {
        for (uint32_t y : st.faces[f]) busy[y] = 1;
      }
      moves.push_back(chosen);
    }
    if (moves.empty()) break;
    const uint32_t made = ApplyLeavingClashesOut(
        moves.size(),
        [&](const std::vector<size_t>& kept, SheetTriangles& out, std::vector<Vec3>& to,
            std::vector<int>& owner) {
          owner.assign(out.faces.size(), -1);
          for (size_t i : kept) {
            to[moves[i].x] = moves[i].to;
            for (uint32_t f : index.faces_of[moves[i].x]) owner[f] = static_cast<int>(i);
          }
        },
        st, v, nullptr);
    if (made == 0) break;
    for (const Move& m : moves) {
      if (v[m.x] == m.to && !moved[m.x]) moved[m.x] = 1, ++opened;
    }
  }
  return opened;
}

}  // namespace sheetmesh
