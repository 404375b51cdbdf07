#include "worker/pipeline/tet/vertex_freedom.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace sheetmesh {

VertexFreedom::VertexFreedom(const TetMesh& mesh, const Vec3& lo, const Vec3& hi,
                             uint32_t input_nodes, double sheet_reach)
    : reach_(sheet_reach) {
  const size_t n = mesh.nodes.size();
  // Which coordinates each vertex may change: none on a sheet; on the box, not the ones
  // that put it on a box face.
  mask_.assign(n, 7);
  const Vec3 ext = hi - lo;
  const double tol = 1e-9 * std::max({std::abs(ext.x), std::abs(ext.y), std::abs(ext.z)});
  for (size_t v = 0; v < n; ++v) {
    for (int k = 0; k < 3; ++k) {
      const double x = mesh.nodes[v][k];
      if (std::abs(x - lo[k]) <= tol || std::abs(x - hi[k]) <= tol) mask_[v] &= ~(1 << k);
    }
  }
  const std::vector<uint8_t> off_box = mask_;
  for (uint32_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.face_piece[f] < 0) continue;
    for (uint32_t v : mesh.faces[f]) mask_[v] = 0;
  }
  ClassifySheetNodes(mesh, input_nodes, off_box);
  if (reach_ > 0) ClassifyPlcSheetNodes(mesh, input_nodes, off_box);
}

Vec3 VertexFreedom::Constrain(uint32_t v, Vec3 d) const {
  switch (slide_[v]) {
    case Slide::kPlane:
      return d - axis_[v] * Dot(d, axis_[v]);
    case Slide::kLine:
      return axis_[v] * Dot(d, axis_[v]);
    case Slide::kBall:
      return d;
    case Slide::kNone:
      break;
  }
  for (int k = 0; k < 3; ++k) {
    if (!(mask_[v] & (1 << k))) d[k] = 0;
  }
  return d;
}

Vec3 VertexFreedom::Place(uint32_t v, const Vec3& p) const {
  switch (slide_[v]) {
    case Slide::kPlane:
      return p - axis_[v] * Dot(p - anchor_[v], axis_[v]);
    case Slide::kLine:
      return anchor_[v] + axis_[v] * Dot(p - anchor_[v], axis_[v]);
    case Slide::kBall: {
      const Vec3 d = p - anchor_[v];
      const double n = Norm(d);
      return n <= reach_of_[v] ? p : anchor_[v] + d * (reach_of_[v] / n);
    }
    case Slide::kNone:
      break;
  }
  return p;
}

uint32_t VertexFreedom::movable() const {
  uint32_t n = 0;
  for (uint32_t v = 0; v < mask_.size(); ++v) n += may_move(v);
  return n;
}

uint32_t VertexFreedom::sliding() const {
  return static_cast<uint32_t>(std::count_if(slide_.begin(), slide_.end(), [](Slide s) {
    return s == Slide::kPlane || s == Slide::kLine;
  }));
}

uint32_t VertexFreedom::in_balls() const {
  return static_cast<uint32_t>(std::count(slide_.begin(), slide_.end(), Slide::kBall));
}

void VertexFreedom::AddFree(const Vec3& p) {
  anchor_.push_back(p);
  mask_.push_back(7);
  slide_.push_back(Slide::kNone);
  axis_.push_back({0, 0, 0});
}

void VertexFreedom::AddInPlane(const Vec3& p, const Vec3& normal) {
  anchor_.push_back(p);
  mask_.push_back(0);
  slide_.push_back(Slide::kPlane);
  axis_.push_back(normal);
}

void VertexFreedom::AddOnBox(const Vec3& p, int k) {
  anchor_.push_back(p);
  mask_.push_back(static_cast<uint8_t>(7 & ~(1 << k)));
  slide_.push_back(Slide::kNone);
  axis_.push_back({0, 0, 0});
}

void VertexFreedom::AddOnLine(const Vec3& p, const Vec3& dir) {
  anchor_.push_back(p);
  mask_.push_back(0);
  slide_.push_back(Slide::kLine);
  axis_.push_back(dir);
}

// Finds the sheet vertices TetGen added (ids from input_nodes on) that may slide: one
// whose sheet faces all belong to one input triangle and close a fan around it lies inside
// that triangle; one whose fans (one per input triangle) each open onto two neighbours on
// one line through it lies on an input edge. Vertices on the box stay where they are.
// off_box[v] == 7: v lies on no box plane.
void VertexFreedom::ClassifySheetNodes(const TetMesh& m, uint32_t input_nodes,
                                       const std::vector<uint8_t>& off_box) {
  auto P = [&](uint32_t v) -> const Vec3& { return m.nodes[v]; };
  slide_.assign(m.nodes.size(), Slide::kNone);
  axis_.assign(m.nodes.size(), Vec3{0, 0, 0});
  anchor_ = m.nodes;
  // Per vertex: (input triangle marker, one of its faces); vertices on the box.
  std::vector<std::vector<std::pair<int32_t, uint32_t>>> faces_of(m.nodes.size());
  std::vector<uint8_t> on_box(m.nodes.size(), 0);
  for (uint32_t f = 0; f < m.faces.size(); ++f) {
    for (uint32_t v : m.faces[f]) {
      if (m.face_piece[f] < 0) {
        on_box[v] = 1;
      } else {
        faces_of[v].push_back({m.face_marker[f], f});
      }
    }
  }
  for (uint32_t v = input_nodes; v < m.nodes.size(); ++v) {
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
        const auto& face = m.faces[fs[j].second];
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

// The PLC's sheet vertices that may move within the ball: off the box, with every sheet
// face around them a whole input triangle (the pieces of a split one must stay in one
// plane). A vertex where sheets meet (faces of two pieces, or an edge in more than two
// faces) moves within kJunctionReach of the reach: the junction's tangles at small r hold
// slivers too, and a shorter move bends the junction's angle less.
void VertexFreedom::ClassifyPlcSheetNodes(const TetMesh& m, uint32_t input_nodes,
                                          const std::vector<uint8_t>& off_box) {
  const uint32_t n = std::min<uint32_t>(input_nodes, static_cast<uint32_t>(m.nodes.size()));
  reach_of_.assign(m.nodes.size(), 0);
  std::vector<int32_t> piece(n, -1);
  std::vector<uint8_t> eligible(n, 0), on_box(n, 0), junction(n, 0);
  std::vector<std::pair<uint64_t, int32_t>> edges;  // (edge key, piece) of sheet faces
  std::vector<int32_t> markers;
  for (uint32_t f = 0; f < m.faces.size(); ++f) {
    if (m.face_piece[f] >= 0) markers.push_back(m.face_marker[f]);
  }
  std::sort(markers.begin(), markers.end());
  auto split = [&](int32_t marker) {
    const auto [lo, hi] = std::equal_range(markers.begin(), markers.end(), marker);
    return hi - lo > 1;
  };
  for (uint32_t f = 0; f < m.faces.size(); ++f) {
    const auto& face = m.faces[f];
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = face[k];
      if (v >= n) continue;
      if (m.face_piece[f] < 0) {
        on_box[v] = 1;
        continue;
      }
      if (piece[v] < 0) {
        piece[v] = m.face_piece[f];
        eligible[v] = 1;
      } else if (piece[v] != m.face_piece[f]) {
        junction[v] = 1;
      }
      if (split(m.face_marker[f])) eligible[v] = 0;
    }
    if (m.face_piece[f] < 0) continue;
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = std::min(face[k], face[(k + 1) % 3]);
      const uint32_t b = std::max(face[k], face[(k + 1) % 3]);
      edges.push_back({(uint64_t{a} << 32) | b, m.face_piece[f]});
    }
  }
  std::sort(edges.begin(), edges.end());
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    if (j - i > 2) {
      for (const uint32_t v : {uint32_t(edges[i].first >> 32), uint32_t(edges[i].first)}) {
        if (v < n) junction[v] = 1;
      }
    }
    i = j;
  }
  for (uint32_t v = 0; v < n; ++v) {
    if (!eligible[v] || on_box[v] || off_box[v] != 7 || slide_[v] != Slide::kNone) continue;
    slide_[v] = Slide::kBall;
    reach_of_[v] = junction[v] ? kJunctionReach * reach_ : reach_;
  }
}

}  // namespace sheetmesh
