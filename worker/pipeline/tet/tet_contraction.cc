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

// The worst quality of u's star and the volume it fills.
struct Star {
  std::vector<uint32_t> tets;
  double worst = 1e300;
  double volume = 0;
};

Star StarOf(const TetMeshEditor& ed, uint32_t u) {
  Star s;
  s.tets = ed.star(u);
  for (uint32_t t : s.tets) {
    const Tet& x = ed.tet(t);
    s.worst = std::min(s.worst, ed.quality(t));
    s.volume += TetVolume(ed.P(x[0]), ed.P(x[1]), ed.P(x[2]), ed.P(x[3]));
  }
  return s;
}

// The tetrahedra of u's star with w for u (those holding w go) into `fill`, if every one is
// positively oriented, none is one of w's star already (that would be a fold: the two
// stars overlapping), together they fill what the star filled, and their worst quality
// beats both the star's and `best`; that worst, or a negative value.
double Contracted(const TetMeshEditor& ed, uint32_t u, uint32_t w, const Star& star, double best,
                  std::vector<Tet>* fill) {
  absl::flat_hash_set<TetKey> around_w;
  for (uint32_t s : ed.star(w)) {
    if (!Has(ed.tet(s), u)) around_w.insert(Sorted(ed.tet(s)));
  }
  double now = 1e300, filled = 0;
  fill->clear();
  for (uint32_t s : star.tets) {
    Tet x = ed.tet(s);
    if (Has(x, w)) continue;
    for (uint32_t& c : x) c = c == u ? w : c;
    const double v = TetVolume(ed.P(x[0]), ed.P(x[1]), ed.P(x[2]), ed.P(x[3]));
    if (!(v > 1e-12 * star.volume) || around_w.contains(Sorted(x))) return -1;
    filled += v;
    now = std::min(now, ed.Quality(x));
    if (!(now > star.worst + kGain) || !(now > best)) return -1;
    fill->push_back(x);
  }
  // More volume than the star's would mean two of the new tetrahedra overlap.
  if (!(std::abs(filled - star.volume) <= 1e-9 * star.volume)) return -1;
  return now;
}

// Whether the sheet faces at u, with w for u (those holding w go), keep the sheets exactly
// where they are: u lies on no box face; w is a corner of u's faces in every input triangle
// u lies on (a vertex inside a sheet triangle goes to a corner of its fan; one on a sheet
// edge, to its neighbour along the edge, an open end of every fan) and in the plane of
// every face it enters; each such face keeps its side and an area, and is not a facet face
// already.
bool SheetFacesFollow(const TetMeshEditor& ed, uint32_t u, uint32_t w) {
  const std::vector<uint32_t>& at_u = ed.sheet_faces_of(u);
  size_t facets_at_u = 0;
  for (uint32_t s : ed.star(u)) {
    const Tet& x = ed.tet(s);
    for (int f = 0; f < 4; ++f) {
      if (x[f] != u && ed.IsFacetFace(TetFace(x, f))) ++facets_at_u;
    }
  }
  // Each sheet face at u is a face of two tetrahedra of u's star; one on the box, of one.
  if (facets_at_u != 2 * at_u.size()) return false;
  const TetMesh& m = ed.mesh();
  auto holds_w = [&](uint32_t f) {
    const auto& face = m.faces[f];
    return face[0] == w || face[1] == w || face[2] == w;
  };
  // w in the closure of every input triangle u lies on: a corner of a face of each (on a
  // flat sheet, the next input triangle's plane is this one's, and the plane alone would
  // let w's faces cover the neighbour's area).
  std::vector<int32_t> with_w;
  for (const uint32_t f : at_u) {
    if (holds_w(f)) with_w.push_back(m.face_marker[f]);
  }
  if (with_w.empty()) return false;
  // Where u's faces in an input triangle do not close around it (u on the triangle's edge),
  // w must be an open end of that fan, on the edge with u: a corner across the triangle
  // would take the faces between u and the edge with it.
  for (const int32_t marker : with_w) {
    std::vector<uint32_t> ends;
    for (const uint32_t f : at_u) {
      if (m.face_marker[f] != marker) continue;
      for (const uint32_t x : m.faces[f]) {
        if (x != u) ends.push_back(x);
      }
    }
    std::sort(ends.begin(), ends.end());
    bool open = false, w_open = false;
    for (size_t i = 0; i < ends.size();) {
      size_t j = i;
      while (j < ends.size() && ends[j] == ends[i]) ++j;
      if (j - i == 1) {
        open = true;
        w_open = w_open || ends[i] == w;
      }
      i = j;
    }
    if (open && !w_open) return false;
  }
  const Vec3 d = ed.P(w) - ed.P(u);
  const double length = Norm(d);
  for (const uint32_t f : at_u) {
    if (std::find(with_w.begin(), with_w.end(), m.face_marker[f]) == with_w.end()) return false;
    if (holds_w(f)) continue;
    const auto& face = m.faces[f];
    const Vec3 n = Cross(ed.P(face[1]) - ed.P(face[0]), ed.P(face[2]) - ed.P(face[0]));
    const double area2 = Norm(n);
    if (!(area2 > 0) || std::abs(Dot(d, n)) > 1e-7 * length * area2) return false;
    std::array<uint32_t, 3> moved = face;
    for (uint32_t& x : moved) x = x == u ? w : x;
    const Vec3 n2 = Cross(ed.P(moved[1]) - ed.P(moved[0]), ed.P(moved[2]) - ed.P(moved[0]));
    if (!(Dot(n, n2) > 1e-6 * area2 * area2)) return false;
    if (ed.IsFacetFace(SortedFace(moved[0], moved[1], moved[2]))) return false;
  }
  return true;
}

// The best of the contractions tried (the one whose new tetrahedra have the best worst),
// and its making: u's star goes, the fill comes.
struct BestContraction {
  uint32_t u = UINT32_MAX, w = UINT32_MAX;
  double worst = -1e300;
  std::vector<Tet> fill, trial;

  void Consider(const TetMeshEditor& ed, uint32_t from, uint32_t to, const Star& star) {
    const double now = Contracted(ed, from, to, star, worst, &trial);
    if (now < 0) return;
    worst = now;
    u = from;
    w = to;
    fill.swap(trial);
  }
  bool Apply(TetMeshEditor& ed) const {
    if (u == UINT32_MAX) return false;
    const std::vector<uint32_t> star = ed.star(u);
    for (uint32_t s : star) ed.Kill(s);
    for (const Tet& x : fill) ed.Add(x);
    return true;
  }
};

}  // namespace

bool ContractEdgeOf(TetMeshEditor& ed, const VertexFreedom& freedom, uint32_t t) {
  const Tet tet = ed.tet(t);
  BestContraction best;
  for (const uint32_t u : tet) {
    if (!freedom.interior(u)) continue;
    const Star star = StarOf(ed, u);
    for (const uint32_t w : tet) {
      if (w != u) best.Consider(ed, u, w, star);
    }
  }
  return best.Apply(ed);
}

bool ContractSheetEdgeOf(TetMeshEditor& ed, const VertexFreedom& freedom, uint32_t t) {
  const Tet tet = ed.tet(t);
  BestContraction best;
  for (const uint32_t u : tet) {
    if (!freedom.slides(u)) continue;
    const Star star = StarOf(ed, u);
    std::vector<uint32_t> link;
    for (uint32_t f : ed.sheet_faces_of(u)) {
      for (uint32_t w : ed.mesh().faces[f]) {
        if (w != u) link.push_back(w);
      }
    }
    std::sort(link.begin(), link.end());
    link.erase(std::unique(link.begin(), link.end()), link.end());
    for (const uint32_t w : link) {
      if (SheetFacesFollow(ed, u, w)) best.Consider(ed, u, w, star);
    }
  }
  if (!best.Apply(ed)) return false;
  ed.ContractSheetFaces(best.u, best.w);
  return true;
}

}  // namespace sheetmesh
