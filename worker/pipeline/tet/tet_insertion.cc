#include "worker/pipeline/tet/tet_insertion.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <utility>

#include "absl/container/flat_hash_set.h"
#include "worker/pipeline/tet/tet_cavity.h"
#include "worker/pipeline/tet/tet_quality.h"

namespace sheetmesh {
namespace {

// Below this, insertion tries many more points (26 more directions and a closer one).
constexpr double kWideSearchDegrees = 15.0;

// The axis a box face lies across: the coordinate its three corners share.
int BoxAxis(const TetMeshEditor& ed, const std::array<uint32_t, 3>& face) {
  for (int k = 0; k < 3; ++k) {
    if (ed.P(face[0])[k] == ed.P(face[1])[k] && ed.P(face[0])[k] == ed.P(face[2])[k]) return k;
  }
  return 0;  // not reached: a box face lies in a plane x_k = const
}

}  // namespace

bool VertexInserter::InsertNear(uint32_t t) {
  // A sliver whose corners have not moved since its last failed try fails again (nearly
  // always): most of the pass's time went into such retries.
  if (ed_.failed(t)) return false;
  ed_.set_failed(t);
  const Tet tet = ed_.tet(t);
  // The new vertex goes inside the facets the sliver lies on (the sum of their inward
  // normals); in a crease of a sheet that may hide the facets of the slivers next to it,
  // so the facets of its neighbours count in a second try. A sliver on no facet tries
  // both sides of its largest face.
  Vec3 own{0, 0, 0}, near{0, 0, 0}, largest{0, 0, 0};
  auto facet_normals = [&](uint32_t x, Vec3* sum) {
    bool any = false;
    for (int f = 0; f < 4; ++f) {
      const auto face = ed_.InwardFace(x, f);
      if (!ed_.IsFacetFace(SortedFace(face[0], face[1], face[2]))) continue;
      const Vec3 normal = Cross(ed_.P(face[1]) - ed_.P(face[0]), ed_.P(face[2]) - ed_.P(face[0]));
      if (!(Norm2(normal) > 0)) continue;
      *sum += Normalized(normal);
      any = true;
    }
    return any;
  };
  const bool on_facet = facet_normals(t, &own);
  near = own;
  for (int f = 0; f < 4; ++f) {
    const auto face = ed_.InwardFace(t, f);
    const Vec3 normal = Cross(ed_.P(face[1]) - ed_.P(face[0]), ed_.P(face[2]) - ed_.P(face[0]));
    if (Norm2(normal) > Norm2(largest)) largest = normal;
    const uint32_t y = ed_.Neighbor(t, f);
    if (y != UINT32_MAX && !ed_.IsFacetFace(TetFace(tet, f))) facet_normals(y, &near);
  }
  std::vector<Vec3> directions;
  for (const Vec3& d :
       on_facet ? std::vector<Vec3>{own, near} : std::vector<Vec3>{largest, largest * -1.0, near}) {
    if (!(Norm2(d) > 0)) continue;
    const Vec3 u = Normalized(d);
    if (std::none_of(directions.begin(), directions.end(),
                     [&](const Vec3& e) { return Dot(e, u) > 1 - 1e-6; })) {
      directions.push_back(u);
    }
  }
  double length = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) length += Norm(ed_.P(tet[i]) - ed_.P(tet[j]));
  length /= 6;
  const Vec3 centre = (ed_.P(tet[0]) + ed_.P(tet[1]) + ed_.P(tet[2]) + ed_.P(tet[3])) / 4.0;
  // The worst tetrahedra (a handful per mesh, wedged between sheets) also try the 26
  // directions of a cube's faces, edges and corners.
  std::vector<double> heights = {0.7, 0.45, 0.25};
  if (ed_.quality(t) < kWideSearchDegrees) {
    for (int x = -1; x <= 1; ++x)
      for (int y = -1; y <= 1; ++y)
        for (int z = -1; z <= 1; ++z) {
          if (x || y || z) directions.push_back(Normalized(Vec3(x, y, z)));
        }
    heights.push_back(0.12);
  }
  // The candidates are measured on all cores (each reads the mesh only) and the best is
  // taken in their order, the first of equals, as one thread would.
  std::vector<Candidate> candidates(directions.size() * heights.size());
  for (size_t i = 0; i < candidates.size(); ++i) {
    candidates[i].p =
        centre + directions[i / heights.size()] * (heights[i % heights.size()] * length);
  }
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, candidates.size(), 2),
      [&](const tbb::blocked_range<size_t>& range) {
        for (size_t i = range.begin(); i != range.end(); ++i) {
          Candidate& c = candidates[i];
          if (!Cavity(ed_, t, c.p, &c.cavity, &c.fill)) {
            c.cavity.clear();
            continue;
          }
          c.quality = 1e300;
          for (const Tet& x : c.fill) {
            c.quality =
                std::min(c.quality, MinDihedralDegrees(ed_.P(x[0]), ed_.P(x[1]), ed_.P(x[2]), c.p));
          }
        }
      });
  Candidate best;
  for (Candidate& c : candidates) {
    if (!c.cavity.empty() && c.quality > best.quality) best = std::move(c);
  }
  auto gain = [&](const Candidate& c) {
    double current = 1e300;
    for (uint32_t x : c.cavity) current = std::min(current, ed_.quality(x));
    return c.quality - current;
  };
  // Where no point off the sheets lifts the sliver above options_.split_sheets_below_degrees, its
  // corners are pinned by the sheets around it; a point on a sheet face or edge near it may do
  // better.
  if (sheet_splits_ &&
      (best.cavity.empty() || !(gain(best) > kGain) ||
       best.quality < options_.split_sheets_below_degrees) &&
      ed_.quality(t) < options_.split_sheets_below_degrees) {
    Candidate split = BestSheetSplit(t);
    if (!split.cavity.empty() && gain(split) > kGain && split.quality > best.quality) {
      best = std::move(split);
    }
  }
  if (best.cavity.empty() || !(gain(best) > kGain)) return false;
  Apply(best);
  return true;
}

void VertexInserter::ConsiderSplit(Candidate c, const std::vector<uint32_t>& seeds,
                                   const absl::flat_hash_set<FaceKey>& opened,
                                   Candidate* best) const {
  std::vector<std::pair<uint32_t, uint32_t>> keep;
  for (uint32_t f : c.split) {
    const auto& face = ed_.mesh().faces[f];
    for (int i = 0; i < 3; ++i) {
      const auto e = std::minmax(face[i], face[(i + 1) % 3]);
      if (e != std::minmax(c.edge[0], c.edge[1])) keep.push_back(e);
    }
  }
  if (!GrowCavity(ed_, c.p, seeds, opened, keep, &c.cavity, &c.fill)) return;
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
    c.quality = std::min(c.quality, MinDihedralDegrees(ed_.P(x[0]), ed_.P(x[1]), ed_.P(x[2]), c.p));
  }
  if (c.quality > best->quality) *best = std::move(c);
}

void VertexInserter::SplitFaceCandidates(uint32_t t, Candidate* best) const {
  const Tet tet = ed_.tet(t);
  // Sheet faces holding an edge of t; and box faces of tetrahedra at t's corners holding
  // one (a sheet vertex just inside the box under a box triangle: the tetrahedron between
  // them is flat however the sheet vertex moves).
  std::vector<uint32_t> faces;
  auto holds_edge = [&](const std::array<uint32_t, 3>& face) {
    int shared = 0;
    for (uint32_t w : face) shared += Has(tet, w);
    return shared >= 2;
  };
  for (uint32_t v : tet) {
    for (uint32_t f : ed_.sheet_faces_of(v)) {
      if (holds_edge(ed_.mesh().faces[f])) faces.push_back(f);
    }
    for (uint32_t s : ed_.star(v)) {
      for (int k = 0; k < 4; ++k) {
        if (ed_.Neighbor(s, k) != UINT32_MAX) continue;
        const uint32_t* index = ed_.FacetFaceIndex(TetFace(ed_.tet(s), k));
        if (index != nullptr && ed_.mesh().face_piece[*index] < 0 &&
            holds_edge(ed_.mesh().faces[*index])) {
          faces.push_back(*index);
        }
      }
    }
  }
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  for (uint32_t f : faces) {
    const auto face = ed_.mesh().faces[f];
    const Vec3 a = ed_.P(face[0]), b = ed_.P(face[1]), c = ed_.P(face[2]);
    const Vec3 normal = Cross(b - a, c - a);
    const double area2 = Norm2(normal);
    if (!(area2 > 0)) continue;
    const FaceKey key = SortedFace(face[0], face[1], face[2]);
    std::vector<uint32_t> seeds;
    for (uint32_t s : ed_.star(face[0])) {
      if (Has(ed_.tet(s), face[1]) && Has(ed_.tet(s), face[2])) seeds.push_back(s);
    }
    const bool on_box = ed_.mesh().face_piece[f] < 0;  // one tetrahedron holds it
    if (seeds.size() != (on_box ? 1u : 2u)) continue;
    const int box_axis = on_box ? BoxAxis(ed_, face) : -1;
    // The sliver must go: it is a seed of the cavity too.
    if (seeds[0] != t && seeds[1] != t) seeds.push_back(t);
    // A grid of points well inside the face (barycentric sixths, none on an edge).
    std::vector<Vec3> points;
    for (int i = 1; i <= 4; ++i)
      for (int j = 1; i + j <= 5; ++j) points.push_back((a * i + b * j + c * (6 - i - j)) / 6.0);
    for (uint32_t w : tet) {
      if (w == face[0] || w == face[1] || w == face[2]) continue;
      // Barycentric coordinates of w's foot, kept 0.15 inside every edge.
      const Vec3 q = ed_.P(w);
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
      // On a box face the point keeps the face's coordinate exactly.
      if (on_box) cand.p[box_axis] = a[box_axis];
      cand.split = {f};
      ConsiderSplit(std::move(cand), seeds, {key}, best);
    }
  }
}

void VertexInserter::SplitEdgeCandidates(uint32_t t, Candidate* best) const {
  const Tet tet = ed_.tet(t);
  // Sheet edges of t.
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j) {
      const uint32_t u = tet[i], w = tet[j];
      std::vector<uint32_t> split;
      bool on_box = false;
      for (uint32_t f : ed_.sheet_faces_of(u)) {
        const auto& face = ed_.mesh().faces[f];
        if (face[0] == w || face[1] == w || face[2] == w) split.push_back(f);
      }
      if (split.empty()) continue;
      std::vector<uint32_t> ring;
      absl::flat_hash_set<FaceKey> opened;
      for (uint32_t s : ed_.star(u)) {
        if (!Has(ed_.tet(s), w)) continue;
        ring.push_back(s);
        for (int f = 0; f < 4; ++f) {
          const FaceKey key = TetFace(ed_.tet(s), f);
          const bool holds = std::find(key.begin(), key.end(), u) != key.end() &&
                             std::find(key.begin(), key.end(), w) != key.end();
          if (!holds) continue;
          const uint32_t* index = ed_.FacetFaceIndex(key);
          if (index == nullptr) continue;
          if (ed_.mesh().face_piece[*index] < 0) on_box = true;
          opened.insert(key);
        }
      }
      if (on_box || opened.size() != split.size()) continue;
      const Vec3 a = ed_.P(u), d = ed_.P(w) - ed_.P(u);
      const double len2 = Norm2(d);
      if (!(len2 > 0)) continue;
      std::vector<double> along = {0.25, 0.375, 0.5, 0.625, 0.75};
      for (uint32_t x : tet) {
        if (x != u && x != w) along.push_back(std::clamp(Dot(ed_.P(x) - a, d) / len2, 0.2, 0.8));
      }
      for (double s : along) {
        Candidate cand;
        cand.p = a + d * s;
        cand.split = split;
        cand.edge = {u, w};
        ConsiderSplit(std::move(cand), ring, opened, best);
      }
    }
}

VertexInserter::Candidate VertexInserter::BestSheetSplit(uint32_t t) const {
  Candidate best;
  SplitFaceCandidates(t, &best);
  SplitEdgeCandidates(t, &best);
  return best;
}

void VertexInserter::Apply(const Candidate& c) {
  for (uint32_t f : c.split) {
    for (uint32_t w : ed_.mesh().faces[f]) fr_.Freeze(w);
  }
  const uint32_t v = ed_.AddNode(c.p);
  if (c.split.empty()) {
    fr_.AddFree(c.p);
  } else if (c.edge[0] == UINT32_MAX && ed_.mesh().face_piece[c.split[0]] < 0) {
    fr_.AddOnBox(c.p, BoxAxis(ed_, ed_.mesh().faces[c.split[0]]));
    ++box_splits_;
  } else if (c.edge[0] == UINT32_MAX) {
    const auto& face = ed_.mesh().faces[c.split[0]];
    fr_.AddInPlane(
        c.p, Normalized(Cross(ed_.P(face[1]) - ed_.P(face[0]), ed_.P(face[2]) - ed_.P(face[0]))));
    ++facet_splits_;
  } else {
    fr_.AddOnLine(c.p, Normalized(ed_.P(c.edge[1]) - ed_.P(c.edge[0])));
    ++edge_splits_;
  }
  for (uint32_t x : c.cavity) ed_.Kill(x);
  for (Tet x : c.fill) {
    x[3] = v;
    ed_.Add(x);
  }
  for (uint32_t f : c.split) {
    const std::array<uint32_t, 3> face = ed_.mesh().faces[f];
    const bool on_sheet = ed_.mesh().face_piece[f] >= 0;
    ed_.EraseFacetFace(SortedFace(face[0], face[1], face[2]));
    for (uint32_t w : face) {
      auto& of = ed_.sheet_faces_of(w);
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
        ed_.mesh().faces[f] = pieces[k];
      } else {
        TetMesh& m = ed_.mesh();
        index = static_cast<uint32_t>(m.faces.size());
        const int32_t marker = m.face_marker[f], piece = m.face_piece[f];
        const float thickness = m.face_thickness_voxels[f];
        m.faces.push_back(pieces[k]);
        m.face_marker.push_back(marker);
        m.face_piece.push_back(piece);
        m.face_thickness_voxels.push_back(thickness);
      }
      ed_.SetFacetFace(SortedFace(pieces[k][0], pieces[k][1], pieces[k][2]), index);
      if (!on_sheet) continue;
      for (uint32_t w : pieces[k]) ed_.sheet_faces_of(w).push_back(index);
    }
  }
  SmoothVertex(ed_, fr_, v, smoothing_);
}

}  // namespace sheetmesh
