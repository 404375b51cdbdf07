#include "worker/pipeline/mesh/aperture_decimate.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <queue>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {
namespace {

using P4 = std::array<double, 4>;  // x, y, z and half the thickness

// Sum of weighted squared distances in R^4: x^T A x + 2 b^T x + c.
struct Quadric {
  Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
  Eigen::Vector4d b = Eigen::Vector4d::Zero();
  double c = 0;

  // The squared distance to the affine subspace through `o` spanned by the orthonormal
  // `dirs`, times w.
  void AddSubspace(const Eigen::Vector4d& o, std::initializer_list<Eigen::Vector4d> dirs,
                   double w) {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    for (const Eigen::Vector4d& e : dirs) m -= e * e.transpose();
    A += w * m;
    b -= w * (m * o);
    c += w * o.dot(m * o);
  }
  Quadric& operator+=(const Quadric& q) {
    A += q.A;
    b += q.b;
    c += q.c;
    return *this;
  }
  double At(const P4& p) const {
    const Eigen::Vector4d x(p[0], p[1], p[2], p[3]);
    return std::max(0.0, x.dot(A * x) + 2 * b.dot(x) + c);
  }
};

Eigen::Vector4d V4(const P4& p) { return Eigen::Vector4d(p[0], p[1], p[2], p[3]); }

struct Candidate {
  double cost;
  uint32_t u, v;  // u goes into v, which moves to `at`
  uint32_t stamp_u, stamp_v;
  P4 at;
  bool operator>(const Candidate& o) const {
    if (cost != o.cost) return cost > o.cost;
    if (u != o.u) return u > o.u;
    return v > o.v;
  }
};

class Decimator {
 public:
  Decimator(TriangleMesh* mesh, const ApertureDecimateOptions& o) : mesh_(*mesh), o_(o) {
    const size_t n = mesh_.vertices.size();
    pos_.resize(n);
    for (size_t v = 0; v < n; ++v) {
      const Vec3& p = mesh_.vertices[v];
      pos_[v] = {p.x, p.y, p.z, 0.5 * mesh_.vertex_thickness_voxels[v]};
    }
    alive_.assign(mesh_.faces.size(), 1);
    faces_of_.resize(n);
    q_.resize(n);
    stamp_.assign(n, 0);
    gone_.assign(n, 0);
    rim_.assign(n, 0);
    feature_.assign(n, 0);
    pinned_.assign(n, 0);
    for (uint32_t f = 0; f < mesh_.faces.size(); ++f) {
      for (uint32_t v : mesh_.faces[f]) faces_of_[v].push_back(f);
    }
    Classify();
    for (uint32_t f = 0; f < mesh_.faces.size(); ++f) AddFaceQuadric(f);
    live_faces_ = mesh_.faces.size();
  }

  ApertureDecimateStats Run() {
    ApertureDecimateStats s;
    s.faces_before = live_faces_;
    shaped_ = o_.min_angle_degrees > 0;
    for (uint32_t v = 0; v < pos_.size(); ++v) PushAround(v);
    while (live_faces_ > o_.triangles) {
      if (heap_.empty()) {
        if (!shaped_) break;
        // Short of the target with the angle bound: the rest without it.
        shaped_ = false;
        for (uint32_t v = 0; v < pos_.size(); ++v) {
          if (!gone_[v]) PushAround(v);
        }
        continue;
      }
      const Candidate c = heap_.top();
      heap_.pop();
      if (gone_[c.u] || gone_[c.v] || stamp_[c.u] != c.stamp_u || stamp_[c.v] != c.stamp_v) {
        continue;
      }
      if (c.cost > o_.max_error) break;
      if (!Collapse(c)) continue;
      ++s.collapses;
      if (!shaped_ && o_.min_angle_degrees > 0) ++s.unshaped_collapses;
      s.largest_error = std::max(s.largest_error, c.cost);
    }
    Compact();
    s.faces_after = mesh_.faces.size();
    return s;
  }

 private:
  // Rims (edges of one face), feature lines (edges of three or more faces, between pieces,
  // or between two vertices marked as features), and the vertices where they branch or end.
  void Classify() {
    absl::flat_hash_map<uint64_t, std::vector<uint32_t>> edge_faces;
    for (uint32_t f = 0; f < mesh_.faces.size(); ++f) {
      const Face& t = mesh_.faces[f];
      for (int k = 0; k < 3; ++k) edge_faces[EdgeKey(t[k], t[(k + 1) % 3])].push_back(f);
    }
    std::vector<std::pair<uint64_t, std::vector<uint32_t>>> edges(edge_faces.begin(),
                                                                  edge_faces.end());
    std::sort(edges.begin(), edges.end());
    std::vector<int> rim_degree(pos_.size(), 0), feature_degree(pos_.size(), 0);
    const auto marked = [&](uint32_t v) { return !o_.feature.empty() && o_.feature[v]; };
    for (const auto& [key, fs] : edges) {
      const uint32_t a = static_cast<uint32_t>(key >> 32), b = static_cast<uint32_t>(key);
      const bool between_pieces = fs.size() == 2 && !mesh_.face_piece.empty() &&
                                  mesh_.face_piece[fs[0]] != mesh_.face_piece[fs[1]];
      if (fs.size() >= 3 || between_pieces || (marked(a) && marked(b))) {
        feature_edges_.insert(key);
        ++feature_degree[a];
        ++feature_degree[b];
        AddEdgePlanes(a, b, fs, o_.feature_weight, /*along_only=*/true);
      } else if (fs.size() == 1) {
        rim_edges_.insert(key);
        ++rim_degree[a];
        ++rim_degree[b];
        AddEdgePlanes(a, b, fs, o_.boundary_weight, /*along_only=*/false);
      }
    }
    for (uint32_t v = 0; v < pos_.size(); ++v) {
      rim_[v] = rim_degree[v] > 0;
      feature_[v] = feature_degree[v] > 0 || marked(v);
      pinned_[v] = (!o_.pinned.empty() && o_.pinned[v]) || (rim_[v] && rim_degree[v] != 2) ||
                   (feature_[v] && feature_degree[v] != 2) || (rim_[v] && feature_[v]);
    }
  }

  // Holds an edge's line: across it in each of its faces' planes (a rim: it moves along
  // itself and within the sheet), or (a feature line) the two planes through it.
  void AddEdgePlanes(uint32_t a, uint32_t b, const std::vector<uint32_t>& fs, double weight,
                     bool along_only) {
    const Vec3 pa(pos_[a][0], pos_[a][1], pos_[a][2]), pb(pos_[b][0], pos_[b][1], pos_[b][2]);
    const Vec3 e = pb - pa;
    const double len2 = Norm2(e);
    if (len2 == 0) return;
    const Vec3 t = e * (1 / std::sqrt(len2));
    Quadric q;
    const Eigen::Vector4d o(pa.x, pa.y, pa.z, 0);
    // Thickness is free along an edge's planes: only position is held.
    const Eigen::Vector4d s(0, 0, 0, 1), along(t.x, t.y, t.z, 0);
    if (along_only) {
      q.AddSubspace(o, {along, s}, weight * len2);
    } else {
      for (uint32_t f : fs) {
        const Vec3 n = UnitNormal(Corners(mesh_, f));
        q.AddSubspace(o, {along, Eigen::Vector4d(n.x, n.y, n.z, 0), s}, weight * len2);
      }
    }
    q_[a] += q;
    q_[b] += q;
  }

  // The plane through the face's corners lifted to (x, t/2): the sheet's walls.
  void AddFaceQuadric(uint32_t f) {
    const Face& t = mesh_.faces[f];
    const Eigen::Vector4d p0 = V4(pos_[t[0]]), p1 = V4(pos_[t[1]]), p2 = V4(pos_[t[2]]);
    Eigen::Vector4d e1 = p1 - p0;
    const double l1 = e1.norm();
    if (l1 == 0) return;
    e1 /= l1;
    Eigen::Vector4d e2 = p2 - p0;
    e2 -= e2.dot(e1) * e1;
    const double l2 = e2.norm();
    if (l2 == 0) return;
    e2 /= l2;
    const double area = Area(Corners(mesh_, f));
    Quadric q;
    q.AddSubspace(p0, {e1, e2}, area);
    for (uint32_t v : t) q_[v] += q;
  }

  std::vector<uint32_t> Neighbours(uint32_t v) const {
    std::vector<uint32_t> out;
    for (uint32_t f : faces_of_[v]) {
      if (!alive_[f]) continue;
      for (uint32_t w : mesh_.faces[f]) {
        if (w != v) out.push_back(w);
      }
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  void PushAround(uint32_t v) {
    if (gone_[v]) return;
    for (uint32_t w : Neighbours(v)) {
      if (v < w) PushEdge(v, w);
    }
  }

  void PushEdge(uint32_t a, uint32_t b) {
    std::optional<Candidate> best;
    for (const auto& [u, v] : {std::pair{a, b}, std::pair{b, a}}) {
      std::optional<Candidate> c = Plan(u, v);
      if (c && (!best || c->cost < best->cost)) best = c;
    }
    if (best) heap_.push(*best);
  }

  // Whether u may go into v, and where v then lies.
  std::optional<Candidate> Plan(uint32_t u, uint32_t v) {
    if (pinned_[u]) return std::nullopt;
    const uint64_t key = EdgeKey(u, v);
    const bool feature_edge = feature_edges_.contains(key), rim_edge = rim_edges_.contains(key);
    if (feature_[u] && !feature_edge) return std::nullopt;  // off its line
    if (rim_[u] && !rim_edge) return std::nullopt;          // inside, or across a gap
    if (!feature_[u] && feature_edge) return std::nullopt;
    if (!rim_[u] && rim_edge) return std::nullopt;
    Quadric q = q_[u];
    q += q_[v];
    // v moves only where it is as free as u: a vertex on a line or rim stays on it.
    std::vector<P4> options;
    const bool v_free = !pinned_[v] && feature_[v] == feature_[u] && rim_[v] == rim_[u];
    if (v_free && !feature_[u]) {
      Eigen::FullPivLU<Eigen::Matrix4d> lu(q.A);
      if (lu.rank() == 4) {
        const Eigen::Vector4d x = lu.solve(-q.b);
        options.push_back({x(0), x(1), x(2), std::max(0.0, x(3))});
      }
      P4 mid;
      for (int k = 0; k < 4; ++k) mid[k] = 0.5 * (pos_[u][k] + pos_[v][k]);
      options.push_back(mid);
    }
    P4 at_v = pos_[v];
    // At v's place, the thickness that costs least.
    if (q.A(3, 3) > 0) {
      const double s =
          -(q.A(3, 0) * at_v[0] + q.A(3, 1) * at_v[1] + q.A(3, 2) * at_v[2] + q.b(3)) / q.A(3, 3);
      at_v[3] = std::max(0.0, s);
    }
    options.push_back(at_v);
    std::optional<Candidate> best;
    for (const P4& at : options) {
      const double cost = q.At(at);
      if (best && cost >= best->cost) continue;
      if (!Valid(u, v, at)) continue;
      best = Candidate{cost, u, v, stamp_[u], stamp_[v], at};
    }
    return best;
  }

  // The link condition (the vertices both share are those of the faces on their edge) and
  // no face of u's or v's turned over or folded.
  bool Valid(uint32_t u, uint32_t v, const P4& at) const {
    std::vector<uint32_t> nu = Neighbours(u), nv = Neighbours(v), common;
    std::set_intersection(nu.begin(), nu.end(), nv.begin(), nv.end(), std::back_inserter(common));
    std::vector<uint32_t> opposite;
    for (uint32_t f : faces_of_[u]) {
      if (!alive_[f]) continue;
      const Face& t = mesh_.faces[f];
      if (t[0] != v && t[1] != v && t[2] != v) continue;
      for (uint32_t w : t) {
        if (w != u && w != v) opposite.push_back(w);
      }
    }
    std::sort(opposite.begin(), opposite.end());
    if (opposite != common || opposite.empty()) return false;
    const double cos_turn = std::cos(o_.max_normal_turn * 3.14159265358979323846 / 180);
    const Vec3 x(at[0], at[1], at[2]);
    for (uint32_t w : {u, v}) {
      for (uint32_t f : faces_of_[w]) {
        if (!alive_[f]) continue;
        const Face& t = mesh_.faces[f];
        const bool has_u = t[0] == u || t[1] == u || t[2] == u;
        const bool has_v = t[0] == v || t[1] == v || t[2] == v;
        if (has_u && has_v) continue;  // it goes
        std::array<Vec3, 3> c = Corners(mesh_, f);
        const Vec3 before = AreaVector(c);
        for (int k = 0; k < 3; ++k) {
          if (t[k] == u || t[k] == v) c[k] = x;
        }
        const Vec3 after = AreaVector(c);
        const double nb = Norm(before), na = Norm(after);
        if (!(na > 1e-9 * (nb + 1e-12)) || na < 1e-6) return false;
        if (Dot(before, after) < cos_turn * nb * na) return false;
        if (shaped_) {
          const double now = MinAngleDegrees(c);
          if (now < o_.min_angle_degrees && now < MinAngleDegrees(Corners(mesh_, f))) {
            return false;
          }
        }
      }
    }
    return true;
  }

  bool Collapse(const Candidate& c) {
    if (!Valid(c.u, c.v, c.at)) return false;
    const uint32_t u = c.u, v = c.v;
    // u's rim and feature edges become v's.
    for (uint32_t x : Neighbours(u)) {
      for (absl::flat_hash_set<uint64_t>* edges : {&rim_edges_, &feature_edges_}) {
        if (edges->erase(EdgeKey(u, x)) > 0 && x != v) edges->insert(EdgeKey(v, x));
      }
    }
    for (uint32_t f : faces_of_[u]) {
      if (!alive_[f]) continue;
      Face& t = mesh_.faces[f];
      if (t[0] == v || t[1] == v || t[2] == v) {
        alive_[f] = 0;
        --live_faces_;
        continue;
      }
      for (uint32_t& w : t) {
        if (w == u) w = v;
      }
      faces_of_[v].push_back(f);
    }
    faces_of_[u].clear();
    gone_[u] = 1;
    pos_[v] = c.at;
    mesh_.vertices[v] = Vec3(c.at[0], c.at[1], c.at[2]);
    q_[v] += q_[u];
    std::vector<uint32_t> kept;
    for (uint32_t f : faces_of_[v]) {
      if (alive_[f]) kept.push_back(f);
    }
    std::sort(kept.begin(), kept.end());
    kept.erase(std::unique(kept.begin(), kept.end()), kept.end());
    faces_of_[v] = std::move(kept);
    ++stamp_[v];
    const std::vector<uint32_t> around = Neighbours(v);
    for (uint32_t w : around) ++stamp_[w];
    PushAround(v);
    for (uint32_t w : around) PushAround(w);
    return true;
  }

  void Compact() {
    std::vector<uint32_t> index(pos_.size(), UINT32_MAX);
    TriangleMesh out;
    out.body_pieces = mesh_.body_pieces;
    for (uint32_t f = 0; f < mesh_.faces.size(); ++f) {
      if (!alive_[f]) continue;
      Face t = mesh_.faces[f];
      for (uint32_t& w : t) {
        if (index[w] == UINT32_MAX) {
          index[w] = static_cast<uint32_t>(out.vertices.size());
          out.vertices.push_back(Vec3(pos_[w][0], pos_[w][1], pos_[w][2]));
          out.vertex_thickness_voxels.push_back(static_cast<float>(2 * pos_[w][3]));
        }
        w = index[w];
      }
      out.faces.push_back(t);
      if (!mesh_.face_piece.empty()) out.face_piece.push_back(mesh_.face_piece[f]);
      out.face_thickness_voxels.push_back((out.vertex_thickness_voxels[t[0]] +
                                           out.vertex_thickness_voxels[t[1]] +
                                           out.vertex_thickness_voxels[t[2]]) /
                                          3);
    }
    mesh_ = std::move(out);
  }

  TriangleMesh& mesh_;
  const ApertureDecimateOptions& o_;
  std::vector<P4> pos_;
  std::vector<uint8_t> alive_;
  std::vector<std::vector<uint32_t>> faces_of_;
  std::vector<Quadric> q_;
  std::vector<uint32_t> stamp_;
  std::vector<uint8_t> gone_, rim_, feature_, pinned_;
  absl::flat_hash_set<uint64_t> rim_edges_, feature_edges_;
  std::priority_queue<Candidate, std::vector<Candidate>, std::greater<Candidate>> heap_;
  uint64_t live_faces_ = 0;
  bool shaped_ = false;  // the angle bound holds
};

}  // namespace

ApertureDecimateStats DecimateWithAperture(TriangleMesh* mesh,
                                           const ApertureDecimateOptions& options) {
  if (mesh->faces.empty()) return {};
  Decimator d(mesh, options);
  return d.Run();
}

}  // namespace sheetmesh
