#include "worker/pipeline/mesh/mesh_topology.h"

#include <algorithm>
#include <numeric>

#include "worker/pipeline/mesh/spatial_grid.h"
#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {
namespace {

struct Dsu {
  std::vector<uint32_t> p;
  explicit Dsu(size_t n) : p(n) { std::iota(p.begin(), p.end(), 0u); }
  uint32_t Find(uint32_t a) {
    while (p[a] != a) a = p[a] = p[p[a]];
    return a;
  }
  void Union(uint32_t a, uint32_t b) { p[Find(a)] = Find(b); }
};

// +1 if face f walks a -> b, -1 if it walks b -> a.
int Direction(const Face& f, uint32_t a, uint32_t b) {
  for (int k = 0; k < 3; ++k) {
    if (f[k] == a && f[(k + 1) % 3] == b) return 1;
    if (f[k] == b && f[(k + 1) % 3] == a) return -1;
  }
  return 0;
}

}  // namespace

EdgeIndex::EdgeIndex(const TriangleMesh& mesh) {
  std::vector<std::pair<uint64_t, uint32_t>> pairs;
  pairs.reserve(mesh.faces.size() * 3);
  for (uint32_t f = 0; f < mesh.faces.size(); ++f) {
    const Face& t = mesh.faces[f];
    for (int k = 0; k < 3; ++k) {
      if (t[k] != t[(k + 1) % 3]) pairs.emplace_back(EdgeKey(t[k], t[(k + 1) % 3]), f);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  faces_.reserve(pairs.size());
  for (size_t i = 0; i < pairs.size();) {
    size_t j = i;
    Edge e;
    e.a = static_cast<uint32_t>(pairs[i].first >> 32);
    e.b = static_cast<uint32_t>(pairs[i].first & 0xFFFFFFFFu);
    e.first = static_cast<uint32_t>(faces_.size());
    while (j < pairs.size() && pairs[j].first == pairs[i].first) {
      if (faces_.size() == e.first || faces_.back() != pairs[j].second) {
        faces_.push_back(pairs[j].second);
      }
      ++j;
    }
    e.count = static_cast<uint32_t>(faces_.size() - e.first);
    edges_.push_back(e);
    i = j;
  }
}

int64_t EdgeIndex::Find(uint32_t a, uint32_t b) const {
  if (a > b) std::swap(a, b);
  auto it = std::lower_bound(edges_.begin(), edges_.end(), std::make_pair(a, b),
                             [](const Edge& e, const std::pair<uint32_t, uint32_t>& k) {
                               return std::make_pair(e.a, e.b) < k;
                             });
  if (it == edges_.end() || it->a != a || it->b != b) return -1;
  return it - edges_.begin();
}

TopologyReport AnalyzeTopology(const TriangleMesh& mesh) {
  TopologyReport r;
  r.vertices = mesh.vertices.size();
  r.faces = mesh.faces.size();
  std::vector<std::array<uint32_t, 3>> sorted(mesh.faces.begin(), mesh.faces.end());
  for (auto& f : sorted) std::sort(f.begin(), f.end());
  std::vector<uint32_t> order(sorted.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(),
            [&](uint32_t a, uint32_t b) { return sorted[a] < sorted[b]; });
  for (size_t i = 1; i < order.size(); ++i)
    r.duplicate_faces += sorted[order[i]] == sorted[order[i - 1]];
  std::vector<uint8_t> used(mesh.vertices.size(), 0);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Face& t = mesh.faces[f];
    for (uint32_t v : t) used[v] = 1;
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || Area(Corners(mesh, f)) < 1e-12) {
      ++r.degenerate_faces;
    }
  }
  for (uint8_t u : used) r.unused_vertices += u == 0;

  const EdgeIndex index(mesh);
  r.edges = index.edges().size();
  Dsu boundary(mesh.vertices.size());
  std::vector<uint8_t> on_boundary(mesh.vertices.size(), 0);
  Dsu pieces(mesh.faces.size());
  for (const EdgeIndex::Edge& e : index.edges()) {
    const uint32_t* fs = index.faces(e);
    for (uint32_t k = 1; k < e.count; ++k) pieces.Union(fs[0], fs[k]);
    if (e.count == 1) {
      ++r.boundary_edges;
      boundary.Union(e.a, e.b);
      on_boundary[e.a] = on_boundary[e.b] = 1;
    } else if (e.count == 2) {
      ++r.manifold_edges;
      if (Direction(mesh.faces[fs[0]], e.a, e.b) == Direction(mesh.faces[fs[1]], e.a, e.b)) {
        ++r.inconsistent_edges;
      }
    } else {
      ++r.nonmanifold_edges;
      r.nonmanifold_edge_list.emplace_back(e.a, e.b);
    }
  }
  for (uint32_t v = 0; v < mesh.vertices.size(); ++v) {
    if (on_boundary[v] && boundary.Find(v) == v) ++r.boundary_loops;
  }
  for (uint32_t f = 0; f < mesh.faces.size(); ++f) r.connected_parts += pieces.Find(f) == f;
  return r;
}

size_t OrientConsistently(TriangleMesh* mesh) {
  const EdgeIndex index(*mesh);
  // Face adjacency across manifold edges.
  std::vector<std::vector<std::pair<uint32_t, int64_t>>> adj(mesh->faces.size());
  for (size_t i = 0; i < index.edges().size(); ++i) {
    const EdgeIndex::Edge& e = index.edges()[i];
    if (e.count != 2) continue;
    const uint32_t* fs = index.faces(e);
    adj[fs[0]].emplace_back(fs[1], static_cast<int64_t>(i));
    adj[fs[1]].emplace_back(fs[0], static_cast<int64_t>(i));
  }
  std::vector<uint8_t> seen(mesh->faces.size(), 0);
  size_t non_orientable = 0;
  std::vector<uint32_t> stack;
  for (uint32_t start = 0; start < mesh->faces.size(); ++start) {
    if (seen[start]) continue;
    seen[start] = 1;
    stack.push_back(start);
    bool bad = false;
    while (!stack.empty()) {
      const uint32_t f = stack.back();
      stack.pop_back();
      for (const auto& [g, ei] : adj[f]) {
        const EdgeIndex::Edge& e = index.edges()[ei];
        const bool same =
            Direction(mesh->faces[f], e.a, e.b) == Direction(mesh->faces[g], e.a, e.b);
        if (!seen[g]) {
          if (same) std::swap(mesh->faces[g][1], mesh->faces[g][2]);
          seen[g] = 1;
          stack.push_back(g);
        } else if (same) {
          bad = true;
        }
      }
    }
    non_orientable += bad;
  }
  return non_orientable;
}

namespace {

// Whether direction s lies in the angle from u to w (all from one point, in the plane of
// normal n = u x w), counting its sides: a touch counts as inside.
bool InAngle(const Vec3& s, const Vec3& u, const Vec3& w, const Vec3& n) {
  const double tol = 1e-9 * Norm(s) * Norm(n) * (Norm(u) + Norm(w));
  return Dot(Cross(u, s), n) >= -tol && Dot(Cross(s, w), n) >= -tol && Dot(s, u + w) > 0;
}

}  // namespace

bool WedgesOverlap(const Vec3& p, const Vec3& a1, const Vec3& a2, const Vec3& b1, const Vec3& b2) {
  const Vec3 u1 = a1 - p, w1 = a2 - p, u2 = b1 - p, w2 = b2 - p;
  const Vec3 n1 = Cross(u1, w1), n2 = Cross(u2, w2);
  const double s1 = Norm(n1), s2 = Norm(n2);
  if (!(s1 > 0) || !(s2 > 0)) return false;  // a degenerate triangle: not this test's
  const Vec3 line = Cross(n1, n2);
  if (Norm(line) <= 1e-9 * s1 * s2) {
    // Coplanar: the angles overlap where an edge or the bisector of one lies strictly
    // within the other (each tested in its own plane's turn).
    auto strictly = [](const Vec3& s, const Vec3& u, const Vec3& w, const Vec3& n) {
      const double tol = 1e-9 * Norm(s) * Norm(n) * (Norm(u) + Norm(w));
      return Dot(Cross(u, s), n) > tol && Dot(Cross(s, w), n) > tol;
    };
    const Vec3 mid1 = Normalized(u1) + Normalized(w1), mid2 = Normalized(u2) + Normalized(w2);
    return strictly(u2, u1, w1, n1) || strictly(w2, u1, w1, n1) || strictly(mid2, u1, w1, n1) ||
           strictly(u1, u2, w2, n2) || strictly(w1, u2, w2, n2) || strictly(mid1, u2, w2, n2);
  }
  // The planes meet in a line through p: the triangles share more than p where the line
  // enters both angles on the same side of p.
  for (const Vec3& s : {line, line * -1.0}) {
    if (InAngle(s, u1, w1, n1) && InAngle(s, u2, w2, n2)) return true;
  }
  return false;
}

bool FacesClash(const std::vector<Vec3>& v, const Face& a, const Face& b,
                double fold_angle_degrees) {
  // The distinct corners they share (a face with a repeated corner counts it once).
  int shared = 0;
  uint32_t sv[3];
  for (int i = 0; i < 3; ++i) {
    const uint32_t x = a[i];
    if ((i > 0 && x == a[0]) || (i > 1 && x == a[1])) continue;
    if (x == b[0] || x == b[1] || x == b[2]) sv[shared++] = x;
  }
  const Triangle ta = {v[a[0]], v[a[1]], v[a[2]]}, tb = {v[b[0]], v[b[1]], v[b[2]]};
  if (shared == 0) return TrianglesIntersect(ta, tb);
  if (shared == 1) {
    const uint32_t p = sv[0];
    uint32_t a1 = 0, a2 = 0, b1 = 0, b2 = 0;
    for (int k = 0; k < 3; ++k) {
      if (a[k] == p) a1 = a[(k + 1) % 3], a2 = a[(k + 2) % 3];
      if (b[k] == p) b1 = b[(k + 1) % 3], b2 = b[(k + 2) % 3];
    }
    return WedgesOverlap(v[p], v[a1], v[a2], v[b1], v[b2]) ||
           TrianglesIntersect(Shrink(ta, 1e-3), Shrink(tb, 1e-3));
  }
  if (shared == 2) {
    uint32_t ra = 0, rb = 0;
    for (uint32_t x : a)
      if (x != sv[0] && x != sv[1]) ra = x;
    for (uint32_t y : b)
      if (y != sv[0] && y != sv[1]) rb = y;
    return DihedralAngleDegrees(v[sv[0]], v[sv[1]], v[ra], v[rb]) < fold_angle_degrees;
  }
  return false;  // the same triangle twice
}

std::vector<std::pair<uint32_t, uint32_t>> FindSelfIntersections(const TriangleMesh& mesh,
                                                                 size_t max_pairs,
                                                                 double fold_angle_degrees) {
  std::vector<std::pair<uint32_t, uint32_t>> out;
  if (mesh.faces.empty()) return out;
  const double cell = std::max(1.0, 2.0 * MeanEdgeLength(mesh));
  SpatialGrid grid(cell);
  std::vector<Vec3> lo(mesh.faces.size()), hi(mesh.faces.size());
  for (uint32_t f = 0; f < mesh.faces.size(); ++f) {
    TriangleBox(Corners(mesh, f), 0.0, &lo[f], &hi[f]);
    grid.Insert(f, lo[f], hi[f]);
  }
  std::vector<uint32_t> stamp(mesh.faces.size(), UINT32_MAX);
  for (uint32_t f = 0; f < mesh.faces.size() && out.size() < max_pairs; ++f) {
    const Face& a = mesh.faces[f];
    grid.Query(lo[f], hi[f], [&](uint32_t g) {
      if (g <= f || stamp[g] == f || out.size() >= max_pairs) return;
      stamp[g] = f;
      const Face& b = mesh.faces[g];
      for (int k = 0; k < 3; ++k) {
        if (hi[f][k] < lo[g][k] || hi[g][k] < lo[f][k]) return;
      }
      if (FacesClash(mesh.vertices, a, b, fold_angle_degrees)) out.emplace_back(f, g);
    });
  }
  return out;
}

}  // namespace sheetmesh
