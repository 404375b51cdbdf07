#include "worker/pipeline/mesh/decimate.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <queue>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
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
  // The point where the quadric is least, when that is well posed (a corner or a crease of
  // planes, not a flat or a line of them).
  bool Minimum(Vec3* p) const {
    const double m00 = a[0], m01 = a[1], m02 = a[2], m11 = a[4], m12 = a[5], m22 = a[7];
    const double c00 = m11 * m22 - m12 * m12, c01 = m02 * m12 - m01 * m22,
                 c02 = m01 * m12 - m02 * m11;
    const double det = m00 * c00 + m01 * c01 + m02 * c02;
    const double scale = m00 + m11 + m22;
    if (!(std::abs(det) > 1e-9 * scale * scale * scale)) return false;
    const double c11 = m00 * m22 - m02 * m02, c12 = m01 * m02 - m00 * m12,
                 c22 = m00 * m11 - m01 * m01;
    const double bx = -a[3], by = -a[6], bz = -a[8];
    *p = Vec3((c00 * bx + c01 * by + c02 * bz) / det, (c01 * bx + c11 * by + c12 * bz) / det,
              (c02 * bx + c12 * by + c22 * bz) / det);
    return true;
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
  uint64_t tie;   // a fixed scramble of the edge's vertex ids
  uint32_t a, b;  // the edge as pushed (Push(a, b)), to try its next option
  uint8_t tried;  // its options tried before, this one among them
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
        rim_(pos_.size(), 0),
        on_box_(pos_.size(), 0) {
    if (o_.keep_box) {
      for (uint32_t v = 0; v < pos_.size(); ++v) on_box_[v] = BoxFaces(pos_[v]);
    }
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
    while (faces > o_.triangles && !heap_.empty()) {
      const Candidate c = heap_.top();
      heap_.pop();
      if (gone_[c.u] || gone_[c.v] || stamp_[c.u] != c.stamp_u || stamp_[c.v] != c.stamp_v) {
        continue;
      }
      if (c.cost > o_.max_error) break;
      const int removed = Collapse(c);
      if (removed < 0) {
        // The edge's next option (with optimal placement: a body's least point may fold a
        // face where an end would not), else none until its faces move.
        const size_t queued = heap_.size();
        if (o_.optimal_placement) Push(c.a, c.b, c.tried);
        if (heap_.size() == queued) refused_.insert(EdgeKey(c.u, c.v));
        continue;
      }
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

  // Whether v has an edge of three or more faces.
  bool OnJunction(uint32_t v) const {
    for (const auto& [w, n] : EdgeFaceCounts(v)) {
      if (n >= 3) return true;
    }
    return false;
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

  // The box faces (bit 2k: low side of axis k, 2k + 1: high) `p` lies in.
  uint8_t BoxFaces(const Vec3& p) const {
    constexpr double kTolerance = 1e-9;
    uint8_t bits = 0;
    for (int k = 0; k < 3; ++k) {
      if (std::abs(p[k] - o_.box_lo[k]) <= kTolerance) bits |= 1 << (2 * k);
      if (std::abs(p[k] - o_.box_hi[k]) <= kTolerance) bits |= 1 << (2 * k + 1);
    }
    return bits;
  }
  // `p` moved into the box faces of `bits`.
  Vec3 OntoBox(Vec3 p, uint8_t bits) const {
    for (int k = 0; k < 3; ++k) {
      if (bits & (1 << (2 * k))) p[k] = o_.box_lo[k];
      if (bits & (1 << (2 * k + 1))) p[k] = o_.box_hi[k];
    }
    return p;
  }

  // Queues the cheaper direction of collapsing edge (a, b), if any is allowed.
  // Options in `tried` (bits) are left out: they were refused.
  void Push(uint32_t a, uint32_t b, uint8_t tried = 0) {
    Quadric q = q_[a];
    q += q_[b];
    // Where the merged vertex may go: a locked vertex stays, a rim vertex stays on the rim.
    std::array<std::pair<uint32_t, Vec3>, 4> options;
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
      const Vec3 mid = (pos_[a] + pos_[b]) * 0.5;
      add(b, mid);
      Vec3 best_point;
      // Not farther from the edge's middle than the edge is long: a quadric of nearly
      // parallel planes has its least point far off, where the faces would fold.
      if (o_.optimal_placement && q.Minimum(&best_point) &&
          Norm2(best_point - mid) <= Norm2(pos_[a] - pos_[b])) {
        add(b, best_point);
      }
    }
    double best = 1e300;
    Vec3 at;
    uint32_t into = b;
    int chosen = -1;
    const uint8_t box = on_box_[a] | on_box_[b];
    for (int k = 0; k < n; ++k) {
      if (tried & (1 << k)) continue;
      // A vertex in a box face stays in it (where two faces meet, on their edge).
      if (box != 0) {
        options[k].second = OntoBox(options[k].second, box);
        if ((BoxFaces(options[k].second) & box) != box) continue;
      }
      const double cost = q.At(options[k].second);
      if (cost < best) {
        best = cost;
        into = options[k].first;
        at = options[k].second;
        chosen = k;
      }
    }
    if (chosen < 0) return;
    const uint32_t from = into == a ? b : a;
    heap_.push({std::max(0.0, best), from, into, stamp_[from], stamp_[into], at,
                Scramble(EdgeKey(a, b)), a, b, static_cast<uint8_t>(tried | (1 << chosen))});
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
    on_box_[v] |= on_box_[u];
    gone_[u] = 1;
    ++stamp_[v];
    // A junction the collapse took away (a pinch where two parts of a body's surface met
    // in an edge) holds its vertices no longer.
    const std::vector<uint32_t> around = Neighbours(v);
    for (uint32_t w : around) locked_[w] = locked_[w] && OnJunction(w);
    locked_[v] = (locked_[v] || locked_[u]) && OnJunction(v);
    // The edges around v may go now, and (with optimal placement) so may refused ones among
    // its neighbours: their faces moved.
    for (uint32_t w : around) {
      refused_.erase(EdgeKey(w, v));
      Push(w, v);
      if (!o_.optimal_placement) continue;
      for (uint32_t x : Neighbours(w)) {
        if (x != v && refused_.erase(EdgeKey(w, x)) > 0) Push(w, x);
      }
    }
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
      if (!mesh_.face_thickness_voxels.empty()) thickness.push_back(mesh_.face_thickness_voxels[f]);
    }
    mesh_.vertices = std::move(vertices);
    mesh_.faces = std::move(faces);
    mesh_.face_piece = std::move(piece);
    mesh_.face_thickness_voxels = std::move(thickness);
    mesh_.vertex_thickness_voxels.clear();
  }

  TriangleMesh& mesh_;
  const DecimateOptions& o_;
  std::vector<Vec3> pos_;
  std::vector<uint8_t> alive_;
  std::vector<std::vector<uint32_t>> faces_of_;
  std::vector<Quadric> q_;
  std::vector<uint32_t> stamp_;
  std::vector<uint8_t> gone_, locked_, rim_;
  std::vector<uint8_t> on_box_;            // BoxFaces of each vertex (with keep_box)
  absl::flat_hash_set<uint64_t> refused_;  // edges whose collapse was refused
  std::priority_queue<Candidate, std::vector<Candidate>, std::greater<Candidate>> heap_;
};

}  // namespace

DecimateStats Decimate(TriangleMesh* mesh, const DecimateOptions& options) {
  if (mesh->faces.size() <= options.triangles) {
    return {mesh->faces.size(), mesh->faces.size(), 0, 0.0};
  }
  return Decimator(mesh, options).Run();
}

}  // namespace sheetmesh
