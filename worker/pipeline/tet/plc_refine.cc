// Local refinement of the PLC's sheet triangles where the volume mesh kept slivers: a
// tetrahedron whose corners all lie on the sheets (two layers of a sheet nearly touching at
// a fold, a rim running just over another sheet) is as flat as the gap between them is
// narrow against the sheet edges that pin it; nothing that moves or adds points off the
// sheets can mend it, but halving those edges doubles its angles.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "worker/pipeline/tet/plc.h"
#include "worker/pipeline/tet/plc_parts.h"

namespace sheetmesh {
namespace {

// Whether the segment a-b lies in one of the box's faces (such an edge is a segment of that
// face's facet too, which a split would have to follow).
bool OnBoxFace(const Vec3& a, const Vec3& b, const Vec3& lo, const Vec3& hi) {
  const double tol = 1e-9 * (1 + Norm(hi - lo));
  for (int k = 0; k < 3; ++k) {
    for (const double side : {lo[k], hi[k]}) {
      if (std::abs(a[k] - side) <= tol && std::abs(b[k] - side) <= tol) return true;
    }
  }
  return false;
}

// Conforming longest-edge bisection of `tris` (an edge is split in every triangle on it):
// each triangle is refined until its longest edge is no longer than its target (squared;
// infinite: none), which both halves of a split keep. An edge is split once it is the
// longest edge of every triangle on it (each triangle with a longer edge is refined along
// that one first), so that no split narrows a triangle's angles to less than half of what
// they were. `hooks.midpoint(a, b)` adds the new vertex and returns it; `hooks.split(f,
// added)` is told that triangle `added` (appended) was cut from f; an edge for which
// `hooks.may_split` says false is not split, and a triangle whose chain reaches one stays.
struct BisectionHooks {
  std::function<double(uint32_t, uint32_t)> length2;
  std::function<bool(uint32_t, uint32_t)> may_split;
  std::function<uint32_t(uint32_t, uint32_t)> midpoint;
  std::function<void(uint32_t, uint32_t)> split;
};

uint32_t Bisect(std::vector<Face>* triangles, std::vector<double> target,
                const BisectionHooks& hooks) {
  std::vector<Face>& tris = *triangles;
  // Each edge's triangles, kept up to date as they split.
  absl::flat_hash_map<uint64_t, std::vector<uint32_t>> faces_of;
  auto link = [&](uint32_t t, bool add) {
    for (int k = 0; k < 3; ++k) {
      std::vector<uint32_t>& on = faces_of[EdgeKey(tris[t][k], tris[t][(k + 1) % 3])];
      if (add) {
        on.push_back(t);
      } else {
        on.erase(std::remove(on.begin(), on.end(), t), on.end());
      }
    }
  };
  for (uint32_t t = 0; t < tris.size(); ++t) link(t, true);
  using Edge = std::pair<uint32_t, uint32_t>;
  // Edges in a strict order: by length, ties by their corners, so that every triangle has
  // one longest edge and a chain of ever longer edges ends.
  auto length2 = [&](const Edge& e) { return hooks.length2(e.first, e.second); };
  auto longer = [&](const Edge& e, const Edge& f) {
    const double le = length2(e), lf = length2(f);
    return le != lf ? le > lf : e > f;
  };
  auto longest_edge = [&](uint32_t t) {
    Edge best{0, 0};
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = tris[t][k], b = tris[t][(k + 1) % 3];
      const Edge e{std::min(a, b), std::max(a, b)};
      if (k == 0 || longer(e, best)) best = e;
    }
    return best;
  };
  auto bisect = [&](const Edge& e) {
    const auto [a, b] = e;
    const std::vector<uint32_t> on_edge = faces_of[EdgeKey(a, b)];
    const uint32_t m = hooks.midpoint(a, b);
    for (const uint32_t f : on_edge) {
      // (.. a .. b ..) -> (.. a .. m ..) and (.. m .. b ..): the same orientation.
      const Face g = tris[f];
      const int ia = g[0] == a ? 0 : g[1] == a ? 1 : 2;
      const int ib = g[0] == b ? 0 : g[1] == b ? 1 : 2;
      Face first = g, second = g;
      first[ib] = m;
      second[ia] = m;
      link(f, false);
      tris[f] = first;
      link(f, true);
      const uint32_t added = static_cast<uint32_t>(tris.size());
      tris.push_back(second);
      target.push_back(target[f]);
      link(added, true);
      hooks.split(f, added);
    }
  };
  uint32_t split = 0;
  std::function<bool(const Edge&)> refine = [&](const Edge& e) {
    if (!hooks.may_split(e.first, e.second)) return false;
    for (;;) {
      const std::vector<uint32_t>& on_edge = faces_of[EdgeKey(e.first, e.second)];
      if (on_edge.empty()) return false;
      std::optional<Edge> first;
      for (const uint32_t f : on_edge) {
        const Edge l = longest_edge(f);
        if (l != e) {
          first = l;
          break;
        }
      }
      if (!first) break;
      if (!refine(*first)) return false;
    }
    bisect(e);
    ++split;
    return true;
  };
  for (bool again = true; again;) {
    again = false;
    for (uint32_t t = 0; t < tris.size(); ++t) {
      if (!(length2(longest_edge(t)) > target[t])) continue;
      if (refine(longest_edge(t))) {
        again = true;
      } else {
        target[t] = std::numeric_limits<double>::infinity();  // its chain reaches a fixed edge
      }
    }
  }
  return split;
}

double LongestEdge2(const Face& f, const std::vector<Vec3>& v) {
  double longest = 0;
  for (int k = 0; k < 3; ++k) longest = std::max(longest, Norm2(v[f[(k + 1) % 3]] - v[f[k]]));
  return longest;
}

}  // namespace

uint32_t RefineSheetTriangles(const std::vector<uint8_t>& marked, Plc* plc) {
  std::vector<Face>& tris = plc->sheet_triangles;
  const size_t vertices_before = plc->vertices.size();
  const size_t first_sheet_facet = plc->facets.size() - tris.size();
  // Each marked triangle is bisected until its longest edge is half what it was (twice for
  // a well-shaped one), the pieces its neighbours' splits cut from it included.
  std::vector<double> target(tris.size(), std::numeric_limits<double>::infinity());
  for (uint32_t t = 0; t < std::min(marked.size(), tris.size()); ++t) {
    if (marked[t]) target[t] = 0.25 * LongestEdge2(tris[t], plc->vertices);
  }
  BisectionHooks hooks;
  hooks.length2 = [&](uint32_t a, uint32_t b) {
    return Norm2(plc->vertices[b] - plc->vertices[a]);
  };
  // An edge in a box face is not split (the face's facet would need the point too).
  hooks.may_split = [&](uint32_t a, uint32_t b) {
    return !OnBoxFace(plc->vertices[a], plc->vertices[b], plc->box_lo, plc->box_hi);
  };
  hooks.midpoint = [&](uint32_t a, uint32_t b) {
    plc->vertices.push_back((plc->vertices[a] + plc->vertices[b]) * 0.5);
    return static_cast<uint32_t>(plc->vertices.size() - 1);
  };
  hooks.split = [&](uint32_t f, uint32_t added) {
    const Face& first = tris[f];
    const Face& second = tris[added];
    plc->facets[first_sheet_facet + f].polygons = {{first[0], first[1], first[2]}};
    plc->sheet_piece.push_back(plc->sheet_piece[f]);
    plc->sheet_thickness.push_back(plc->sheet_thickness[f]);
    plc->facets.push_back(
        {{{second[0], second[1], second[2]}}, kFirstSheetMarker + static_cast<int32_t>(added)});
  };
  const uint32_t split = Bisect(&tris, std::move(target), hooks);
  // The lattice seeds stay the last vertices (MoveSeeds moves those, and they are on no
  // facet): the midpoints go before them.
  const size_t seeds = plc->seed_points;
  if (seeds > 0 && plc->vertices.size() > vertices_before) {
    const size_t first_seed = vertices_before - seeds;
    std::rotate(plc->vertices.begin() + static_cast<std::ptrdiff_t>(first_seed),
                plc->vertices.begin() + static_cast<std::ptrdiff_t>(vertices_before),
                plc->vertices.end());
    auto remap = [&](uint32_t& i) {
      if (i >= vertices_before) i -= static_cast<uint32_t>(seeds);
    };
    for (PlcFacet& f : plc->facets) {
      for (auto& polygon : f.polygons) {
        for (uint32_t& i : polygon) remap(i);
      }
    }
    for (Face& t : tris) {
      for (uint32_t& i : t) remap(i);
    }
  }
  return split;
}

uint32_t SplitLongSheetEdges(double max_edge, std::vector<Vec3>* vertices,
                             std::vector<uint8_t>* on_face, SheetTriangles* st) {
  if (!(max_edge > 0)) return 0;
  std::vector<Vec3>& v = *vertices;
  on_face->resize(v.size(), 0);
  BisectionHooks hooks;
  hooks.length2 = [&](uint32_t a, uint32_t b) { return Norm2(v[b] - v[a]); };
  hooks.may_split = [](uint32_t, uint32_t) { return true; };
  hooks.midpoint = [&](uint32_t a, uint32_t b) {
    v.push_back((v[a] + v[b]) * 0.5);
    // On the box faces both ends are on (an edge along the box keeps its midpoint on it).
    on_face->push_back((*on_face)[a] & (*on_face)[b]);
    return static_cast<uint32_t>(v.size() - 1);
  };
  hooks.split = [&](uint32_t f, uint32_t) {
    st->source.push_back(st->source[f]);
    st->piece.push_back(st->piece[f]);
    st->thickness.push_back(st->thickness[f]);
  };
  return Bisect(&st->faces, std::vector<double>(st->faces.size(), max_edge * max_edge), hooks);
}

uint32_t DropSheetTriangles(const std::vector<uint8_t>& drop, Plc* plc) {
  const size_t first_sheet_facet = plc->facets.size() - plc->sheet_triangles.size();
  Plc kept_only = *plc;
  kept_only.facets.resize(first_sheet_facet);
  kept_only.sheet_triangles.clear();
  kept_only.sheet_piece.clear();
  kept_only.sheet_thickness.clear();
  uint32_t dropped = 0;
  for (size_t t = 0; t < plc->sheet_triangles.size(); ++t) {
    if (t < drop.size() && drop[t]) {
      ++dropped;
      continue;
    }
    const Face& f = plc->sheet_triangles[t];
    kept_only.facets.push_back(
        {{{f[0], f[1], f[2]}},
         kFirstSheetMarker + static_cast<int32_t>(kept_only.sheet_triangles.size())});
    kept_only.sheet_triangles.push_back(f);
    kept_only.sheet_piece.push_back(plc->sheet_piece[t]);
    kept_only.sheet_thickness.push_back(plc->sheet_thickness[t]);
  }
  *plc = std::move(kept_only);
  return dropped;
}

}  // namespace sheetmesh
