#include "worker/pipeline/mesh/decimate.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <queue>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {
namespace {

// A symmetric 4 x 4 quadric: the sum of squared distances to weighted planes.
struct Quadric {
  double a[10] = {};  // xx xy xz xw yy yz yw zz zw ww

  void AddPlane(const Vec3& n, double d, double w) {
    const double p[4] = {n.x, n.y, n.z, d};
    int k = 0;
    for (int i = 0; i < 4; ++i)
      for (int j = i; j < 4; ++j) a[k++] += w * p[i] * p[j];
  }
  Quadric& operator+=(const Quadric& o) {
    for (int k = 0; k < 10; ++k) a[k] += o.a[k];
    return *this;
  }
  double At(const Vec3& p) const {
    const double x = p.x, y = p.y, z = p.z;
    return a[0] * x * x + 2 * a[1] * x * y + 2 * a[2] * x * z + 2 * a[3] * x + a[4] * y * y +
           2 * a[5] * y * z + 2 * a[6] * y + a[7] * z * z + 2 * a[8] * z + a[9];
  }
};

struct Candidate {
  double cost;
  uint32_t u, v;  // u goes into v
  uint32_t stamp_u, stamp_v;
  Vec3 at;
  uint64_t tie;  // a fixed scramble of the edge's vertex ids
  // Ties (a flat sheet's edges all cost 0) go by the scramble: the same order every run, but
  // spread over the sheet — an order swept along the vertex numbering, or by edge length,
  // leaves collapses blocked early (a planar junction stopped at 120 of 100 triangles).
  bool operator>(const Candidate& o) const {
    if (cost != o.cost) return cost > o.cost;
    if (tie != o.tie) return tie > o.tie;
    if (u != o.u) return u > o.u;
    return v > o.v;
  }
};

// SplitMix64's finaliser: a fixed, well-spread permutation of 64-bit keys.
uint64_t Scramble(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

Face Sorted(Face f) {
  std::sort(f.begin(), f.end());
  return f;
}

class Decimator {
 public:
  Decimator(TriangleMesh* mesh, const DecimateOptions& o)
      : mesh_(*mesh),
        o_(o),
        pos_(mesh->vertices),
        alive_(mesh->faces.size(), 1),
        faces_of_(pos_.size()),
        q_(pos_.size()),
        stamp_(pos_.size(), 0),
        gone_(pos_.size(), 0),
        locked_(pos_.size(), 0),
        rim_(pos_.size(), 0) {
    for (uint32_t f = 0; f < mesh_.faces.size(); ++f) {
      for (uint32_t v : mesh_.faces[f]) faces_of_[v].push_back(f);
    }
    absl::flat_hash_map<uint64_t, std::vector<uint32_t>> edge_faces;
    for (uint32_t f = 0; f < mesh_.faces.size(); ++f) {
      const Face& t = mesh_.faces[f];
      const Vec3 area = AreaVector(Corners(mesh_, f));
      const double len = Norm(area);
      if (len > 0) {
        const Vec3 n = area * (1.0 / len);
        for (uint32_t v : t) q_[v].AddPlane(n, -Dot(n, pos_[t[0]]), 0.5 * len);
      }
      for (int k = 0; k < 3; ++k) edge_faces[EdgeKey(t[k], t[(k + 1) % 3])].push_back(f);
    }
    // In key order: the quadrics' sums and the heap's pushes must not follow the hash
    // table's order, which differs between tables.
    std::vector<std::pair<uint64_t, std::vector<uint32_t>>> edges(edge_faces.begin(),
                                                                  edge_faces.end());
    edge_faces = {};
    std::sort(edges.begin(), edges.end());
    // Rims, junctions and seams between pieces.
    for (const auto& [key, fs] : edges) {
      const uint32_t a = static_cast<uint32_t>(key >> 32), b = static_cast<uint32_t>(key);
      if (fs.size() >= 3) {
        locked_[a] = locked_[b] = 1;
        continue;
      }
      const bool seam = fs.size() == 2 && !mesh_.face_piece.empty() &&
                        mesh_.face_piece[fs[0]] != mesh_.face_piece[fs[1]];
      if (fs.size() != 1 && !seam) continue;
      rim_[a] = rim_[b] = 1;
      for (uint32_t f : fs) {
        const Vec3 n = UnitNormal(Corners(mesh_, f));
        const Vec3 e = pos_[b] - pos_[a];
        const Vec3 m = Normalized(Cross(e, n));
        if (Norm2(m) == 0) continue;
        const double w = o_.boundary_weight * Norm2(e);
        q_[a].AddPlane(m, -Dot(m, pos_[a]), w);
        q_[b].AddPlane(m, -Dot(m, pos_[a]), w);
      }
    }
    for (const auto& [key, fs] : edges) {
      Push(static_cast<uint32_t>(key >> 32), static_cast<uint32_t>(key));
    }
  }

  DecimateStats Run() {
    DecimateStats s;
    s.faces_before = mesh_.faces.size();
    uint64_t faces = s.faces_before;
    while (faces > o_.target_faces && !heap_.empty()) {
      const Candidate c = heap_.top();
      heap_.pop();
      if (gone_[c.u] || gone_[c.v] || stamp_[c.u] != c.stamp_u || stamp_[c.v] != c.stamp_v) {
        continue;
      }
      if (c.cost > o_.max_error) break;
      const int removed = Collapse(c);
      if (removed < 0) continue;
      faces -= removed;
      ++s.collapses;
      s.largest_error = std::max(s.largest_error, c.cost);
    }
    Compact();
    s.faces_after = mesh_.faces.size();
    return s;
  }

 private:
  std::vector<uint32_t> Neighbours(uint32_t v) const {
    std::vector<uint32_t> n;
    for (uint32_t f : faces_of_[v]) {
      if (!alive_[f]) continue;
      for (uint32_t w : mesh_.faces[f]) {
        if (w != v) n.push_back(w);
      }
    }
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
    return n;
  }

  // How many alive faces share the edge (v, w), for every neighbour w of v.
  std::vector<std::pair<uint32_t, int>> EdgeFaceCounts(uint32_t v) const {
    std::vector<uint32_t> ends;
    for (uint32_t f : faces_of_[v]) {
      if (!alive_[f]) continue;
      for (uint32_t w : mesh_.faces[f]) {
        if (w != v) ends.push_back(w);
      }
    }
    std::sort(ends.begin(), ends.end());
    std::vector<std::pair<uint32_t, int>> counts;
    for (uint32_t w : ends) {
      if (counts.empty() || counts.back().first != w) counts.push_back({w, 0});
      ++counts.back().second;
    }
    return counts;
  }

  // A vertex on junction curves (edges of three or more faces) that may slide along them:
  // it has no boundary edge (where a curve reaches a rim, the vertex stays). The faces'
  // quadrics, planes of every sheet meeting there, keep a curve straight and a point where
  // curves meet in place.
  bool MayFollowJunction(uint32_t v) const {
    for (const auto& [w, n] : EdgeFaceCounts(v)) {
      if (n == 1) return false;
    }
    return true;
  }

  // Queues the cheaper direction of collapsing edge (a, b), if any is allowed.
  void Push(uint32_t a, uint32_t b) {
    Quadric q = q_[a];
    q += q_[b];
    // Where the merged vertex may go: a locked vertex stays, a rim vertex stays on the rim.
    std::array<std::pair<uint32_t, Vec3>, 3> options;
    int n = 0;
    auto add = [&](uint32_t into, const Vec3& at) { options[n++] = {into, at}; };
    if (locked_[a] && locked_[b]) {
      // Along a junction curve: an inner vertex of the curve goes into its neighbour.
      int shared = 0;
      for (const auto& [w, count] : EdgeFaceCounts(a)) shared += w == b ? count : 0;
      if (shared < 3) return;
      if (MayFollowJunction(a)) add(b, pos_[b]);
      if (MayFollowJunction(b)) add(a, pos_[a]);
      if (n == 0) return;
    } else if (locked_[a] || locked_[b]) {
      const uint32_t keep = locked_[a] ? a : b;
      add(keep, pos_[keep]);
    } else if (rim_[a] != rim_[b]) {
      const uint32_t keep = rim_[a] ? a : b;
      add(keep, pos_[keep]);
    } else {
      add(b, pos_[a]);  // the survivor's index does not matter: positions do
      add(b, pos_[b]);
      add(b, (pos_[a] + pos_[b]) * 0.5);
    }
    double best = 1e300;
    Vec3 at;
    uint32_t into = b;
    for (int k = 0; k < n; ++k) {
      const double cost = q.At(options[k].second);
      if (cost < best) {
        best = cost;
        into = options[k].first;
        at = options[k].second;
      }
    }
    const uint32_t from = into == a ? b : a;
    heap_.push(
        {std::max(0.0, best), from, into, stamp_[from], stamp_[into], at, Scramble(EdgeKey(a, b))});
  }

  // Collapses c.u into c.v at c.at; the faces removed, or -1 when not allowed.
  int Collapse(const Candidate& c) {
    const uint32_t u = c.u, v = c.v;
    // Faces on the edge, and the link condition: the common neighbours are their corners.
    std::vector<uint32_t> shared;
    for (uint32_t f : faces_of_[u]) {
      if (alive_[f] &&
          std::find(mesh_.faces[f].begin(), mesh_.faces[f].end(), v) != mesh_.faces[f].end()) {
        shared.push_back(f);
      }
    }
    if (shared.empty() || (shared.size() > 2 && !(locked_[u] && locked_[v]))) return -1;
    const std::vector<uint32_t> nu = Neighbours(u), nv = Neighbours(v);
    std::vector<uint32_t> common;
    std::set_intersection(nu.begin(), nu.end(), nv.begin(), nv.end(), std::back_inserter(common));
    if (common.size() != shared.size()) return -1;
    if (shared.size() == 2 && rim_[u] && rim_[v]) return -1;  // would pinch the rim
    // A collapse may not take a piece's last faces: some face of u or v must remain.
    size_t remaining = 0;
    for (uint32_t w : {u, v}) {
      for (uint32_t f : faces_of_[w]) {
        remaining += alive_[f] && std::find(shared.begin(), shared.end(), f) == shared.end();
      }
    }
    if (remaining == 0) return -1;
    // Around a junction the link condition does not rule out two faces becoming one.
    if (shared.size() > 2) {
      std::vector<Face> at_v;
      for (uint32_t f : faces_of_[v]) {
        if (alive_[f]) at_v.push_back(Sorted(mesh_.faces[f]));
      }
      std::sort(at_v.begin(), at_v.end());
      for (uint32_t f : faces_of_[u]) {
        if (!alive_[f] || std::find(shared.begin(), shared.end(), f) != shared.end()) continue;
        Face g = mesh_.faces[f];
        for (uint32_t& x : g) x = x == u ? v : x;
        if (std::binary_search(at_v.begin(), at_v.end(), Sorted(g))) return -1;
      }
    }
    // No face may flip, fold or degenerate.
    const double turn = std::cos(o_.max_normal_turn * 3.14159265358979323846 / 180.0);
    for (uint32_t w : {u, v}) {
      for (uint32_t f : faces_of_[w]) {
        if (!alive_[f] || std::find(shared.begin(), shared.end(), f) != shared.end()) continue;
        Triangle before = Corners(mesh_, f), after = before;
        for (int k = 0; k < 3; ++k) {
          before[k] = pos_[mesh_.faces[f][k]];
          after[k] = mesh_.faces[f][k] == u || mesh_.faces[f][k] == v ? c.at : before[k];
        }
        const Vec3 n0 = AreaVector(before), n1 = AreaVector(after);
        const double l0 = Norm(n0), l1 = Norm(n1);
        if (!(l1 > 1e-6 * std::max(1.0, l0))) return -1;
        if (Dot(n0, n1) < turn * l0 * l1) return -1;
        if (MinAngleDegrees(after) < 1.0) return -1;
      }
    }
    for (uint32_t f : shared) alive_[f] = 0;
    for (uint32_t f : faces_of_[u]) {
      if (!alive_[f]) continue;
      for (uint32_t& x : mesh_.faces[f]) {
        if (x == u) x = v;
      }
      faces_of_[v].push_back(f);
    }
    faces_of_[u].clear();
    std::vector<uint32_t>& fv = faces_of_[v];
    fv.erase(std::remove_if(fv.begin(), fv.end(), [&](uint32_t f) { return !alive_[f]; }),
             fv.end());
    std::sort(fv.begin(), fv.end());
    fv.erase(std::unique(fv.begin(), fv.end()), fv.end());
    q_[v] += q_[u];
    pos_[v] = c.at;
    rim_[v] = rim_[v] || rim_[u];
    gone_[u] = 1;
    ++stamp_[v];
    for (uint32_t w : Neighbours(v)) Push(w, v);
    return static_cast<int>(shared.size());
  }

  void Compact() {
    std::vector<uint32_t> index(pos_.size(), UINT32_MAX);
    std::vector<Vec3> vertices;
    std::vector<Face> faces;
    std::vector<int32_t> piece;
    std::vector<float> thickness;
    for (uint32_t f = 0; f < mesh_.faces.size(); ++f) {
      if (!alive_[f]) continue;
      Face g;
      for (int k = 0; k < 3; ++k) {
        uint32_t& i = index[mesh_.faces[f][k]];
        if (i == UINT32_MAX) {
          i = static_cast<uint32_t>(vertices.size());
          vertices.push_back(pos_[mesh_.faces[f][k]]);
        }
        g[k] = i;
      }
      faces.push_back(g);
      if (!mesh_.face_piece.empty()) piece.push_back(mesh_.face_piece[f]);
      if (!mesh_.face_thickness.empty()) thickness.push_back(mesh_.face_thickness[f]);
    }
    mesh_.vertices = std::move(vertices);
    mesh_.faces = std::move(faces);
    mesh_.face_piece = std::move(piece);
    mesh_.face_thickness = std::move(thickness);
    mesh_.vertex_thickness.clear();
  }

  TriangleMesh& mesh_;
  const DecimateOptions& o_;
  std::vector<Vec3> pos_;
  std::vector<uint8_t> alive_;
  std::vector<std::vector<uint32_t>> faces_of_;
  std::vector<Quadric> q_;
  std::vector<uint32_t> stamp_;
  std::vector<uint8_t> gone_, locked_, rim_;
  std::priority_queue<Candidate, std::vector<Candidate>, std::greater<Candidate>> heap_;
};

}  // namespace

DecimateStats Decimate(TriangleMesh* mesh, const DecimateOptions& options) {
  if (mesh->faces.size() <= options.target_faces) {
    return {mesh->faces.size(), mesh->faces.size(), 0, 0.0};
  }
  return Decimator(mesh, options).Run();
}

}  // namespace sheetmesh
