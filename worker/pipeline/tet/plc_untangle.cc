// Untangles sheet triangles that cut through each other, by local moves that keep every
// triangle: a vertex of a clashing pair moved (toward the middle of its neighbours, or off
// the other triangle's plane, by at most max_move voxels), else an edge of the pair flipped.
// The surface's later steps (decimation, smoothing, wall fitting, the rim push) and the
// snapping onto the box can leave a sheet folded over itself at a vertex, or two sheets
// crossing by a fraction of a voxel; a move of that size mends it where the image cannot
// tell the difference.
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "absl/container/flat_hash_set.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/mesh/spatial_grid.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/plc_parts.h"

namespace sheetmesh {
namespace {

constexpr double kMinMovedAngle = 1.0;  // degrees: a move may not make a sliver triangle
constexpr int kMaxRounds = 12;

Triangle TriangleOf(const std::vector<Vec3>& v, const Face& f) {
  return {v[f[0]], v[f[1]], v[f[2]]};
}

class Untangler {
 public:
  Untangler(SheetTriangles& st, std::vector<Vec3>& v, const std::vector<uint8_t>& on_face,
            double max_move)
      : st_(st), v_(v), on_face_(on_face), max_move_(max_move) {}

  UntangleStats Run() {
    UntangleStats stats;
    for (int round = 0; round < kMaxRounds; ++round) {
      TriangleMesh mesh;
      mesh.vertices = v_;
      mesh.faces = st_.faces;
      const auto pairs = FindSelfIntersections(mesh, 100000, 1.0);
      stats.remaining_pairs = static_cast<uint32_t>(pairs.size());
      if (round == 0) stats.found_pairs = stats.remaining_pairs;
      if (pairs.empty()) break;
      Index();
      std::vector<uint8_t> touched(st_.faces.size(), 0);
      uint32_t mended = 0;
      for (const auto& [a, b] : pairs) {
        if (touched[a] || touched[b]) continue;
        if (MoveAVertex(a, b, &touched, &stats) || FlipAnEdge(a, b, &touched, &stats)) ++mended;
      }
      if (mended == 0) break;
    }
    return stats;
  }

 private:
  // The faces of each vertex, the face grid (boxes grown by what moves may add), the
  // original normals.
  void Index() {
    around_.assign(v_.size(), {});
    for (uint32_t f = 0; f < st_.faces.size(); ++f) {
      for (uint32_t u : st_.faces[f]) around_[u].push_back(f);
    }
    double edges = 0;
    for (const Face& f : st_.faces) {
      for (int k = 0; k < 3; ++k) edges += Norm(v_[f[(k + 1) % 3]] - v_[f[k]]);
    }
    const double mean = st_.faces.empty() ? 1.0 : edges / (3.0 * st_.faces.size());
    grid_ = SpatialGrid(std::max(1.0, 2.0 * mean));
    for (uint32_t f = 0; f < st_.faces.size(); ++f) {
      Vec3 lo, hi;
      TriangleBox(TriangleOf(v_, st_.faces[f]), 2 * max_move_, &lo, &hi);
      grid_.Insert(f, lo, hi);
    }
  }

  // Whether the faces in `changed` (as they are now in v_/st_) clash with any face, or a
  // face of them is a sliver or faces away from `normals` (the sheet's side there).
  bool Clean(const std::vector<uint32_t>& changed, const std::vector<Vec3>& normals) {
    absl::flat_hash_set<uint32_t> own(changed.begin(), changed.end());
    for (size_t i = 0; i < changed.size(); ++i) {
      const Face& f = st_.faces[changed[i]];
      const Triangle t = TriangleOf(v_, f);
      if (MinAngleDegrees(t) < kMinMovedAngle) return false;
      if (Dot(UnitNormal(t), normals[i]) <= 0) return false;
      Vec3 lo, hi;
      TriangleBox(t, 0.0, &lo, &hi);
      bool clash = false;
      grid_.Query(lo, hi, [&](uint32_t g) {
        if (clash || g == changed[i] || (own.contains(g) && g < changed[i])) return;
        clash = FacesClash(v_, f, st_.faces[g], 1.0);
      });
      if (clash) return false;
    }
    return true;
  }

  // Moves one vertex of the pair so that neither of its faces clashes with anything.
  bool MoveAVertex(uint32_t a, uint32_t b, std::vector<uint8_t>* touched, UntangleStats* stats) {
    std::vector<uint32_t> corners;
    for (uint32_t f : {a, b}) {
      for (uint32_t u : st_.faces[f]) {
        if (std::find(corners.begin(), corners.end(), u) == corners.end()) corners.push_back(u);
      }
    }
    for (uint32_t u : corners) {
      const uint8_t faces_on = on_face_[u];
      if (faces_on != 0 && (faces_on & (faces_on - 1)) != 0) continue;  // a box edge or corner
      const uint32_t other =
          std::find(st_.faces[a].begin(), st_.faces[a].end(), u) != st_.faces[a].end() ? b : a;
      const std::vector<uint32_t>& star = around_[u];
      // The sheet's side here: its star's area-weighted normal, which a face folded back
      // (a minority) turns against. After the move every face of the star must face it.
      Vec3 side_normal(0, 0, 0);
      for (uint32_t f : star) side_normal = side_normal + AreaVector(TriangleOf(v_, st_.faces[f]));
      side_normal = Normalized(side_normal);
      const std::vector<Vec3> normals(star.size(), side_normal);
      // The middle of its neighbours, and off the other triangle's plane on its own side.
      Vec3 middle(0, 0, 0);
      int n = 0;
      for (uint32_t f : star) {
        for (uint32_t w : st_.faces[f]) {
          if (w != u) middle = middle + v_[w], ++n;
        }
      }
      middle = middle * (1.0 / std::max(1, n));
      const Triangle ot = TriangleOf(v_, st_.faces[other]);
      const Vec3 on = UnitNormal(ot);
      const double side = Dot(v_[u] - ot[0], on) >= 0 ? 1.0 : -1.0;
      std::vector<Vec3> steps;
      for (double t : {0.25, 0.5, 1.0}) steps.push_back((middle - v_[u]) * t);
      for (double d : {0.25, 0.5, 1.0}) steps.push_back(on * (side * d * max_move_));
      for (double d : {0.25, 0.5, 1.0}) steps.push_back(on * (-side * d * max_move_));
      const Vec3 from = v_[u];
      for (Vec3 step : steps) {
        if (faces_on != 0) {  // stays in its box face
          for (int k = 0; k < 3; ++k) {
            if (faces_on & (3 << (2 * k))) step[k] = 0;
          }
        }
        const double len = Norm(step);
        if (len < 1e-9) continue;
        if (len > max_move_) step = step * (max_move_ / len);
        v_[u] = from + step;
        if (Clean(star, normals)) {
          for (uint32_t f : star) (*touched)[f] = 1;
          ++stats->moved_vertices;
          stats->max_move = std::max(stats->max_move, Norm(step));
          return true;
        }
      }
      v_[u] = from;
    }
    return false;
  }

  // Flips an edge of the pair shared with one other face of its piece, where that leaves
  // no clash.
  bool FlipAnEdge(uint32_t a, uint32_t b, std::vector<uint8_t>* touched, UntangleStats* stats) {
    for (uint32_t f : {a, b}) {
      for (int k = 0; k < 3; ++k) {
        const uint32_t x = st_.faces[f][k], y = st_.faces[f][(k + 1) % 3];
        const uint32_t z1 = st_.faces[f][(k + 2) % 3];
        uint32_t g = UINT32_MAX;
        int count = 0;
        for (uint32_t h : around_[x]) {
          if (h == f) continue;
          const Face& hf = st_.faces[h];
          if (std::find(hf.begin(), hf.end(), y) != hf.end()) g = h, ++count;
        }
        if (count != 1 || st_.piece[g] != st_.piece[f]) continue;
        uint32_t z2 = UINT32_MAX;
        for (uint32_t w : st_.faces[g]) {
          if (w != x && w != y) z2 = w;
        }
        if (z2 == UINT32_MAX || z2 == z1) continue;
        bool exists = false;  // the new edge may not be there already
        for (uint32_t h : around_[z1]) {
          const Face& hf = st_.faces[h];
          exists = exists || std::find(hf.begin(), hf.end(), z2) != hf.end();
        }
        if (exists) continue;
        const Face old_f = st_.faces[f], old_g = st_.faces[g];
        const Vec3 side =
            Normalized(AreaVector(TriangleOf(v_, old_f)) + AreaVector(TriangleOf(v_, old_g)));
        const std::vector<Vec3> normals = {side, side};
        st_.faces[f] = {x, z2, z1};  // x -> y -> z1 kept its turn: x, z2, z1 and y, z1, z2
        st_.faces[g] = {y, z1, z2};
        if (Clean({f, g}, normals)) {
          Reindex(f, old_f);
          Reindex(g, old_g);
          (*touched)[f] = (*touched)[g] = 1;
          ++stats->flipped_edges;
          return true;
        }
        st_.faces[f] = old_f;
        st_.faces[g] = old_g;
      }
    }
    return false;
  }

  // Face f changed its corners from `old`: the vertex index follows.
  void Reindex(uint32_t f, const Face& old) {
    for (uint32_t u : old) {
      auto& list = around_[u];
      list.erase(std::remove(list.begin(), list.end(), f), list.end());
    }
    for (uint32_t u : st_.faces[f]) around_[u].push_back(f);
  }

  SheetTriangles& st_;
  std::vector<Vec3>& v_;
  const std::vector<uint8_t>& on_face_;
  double max_move_;
  std::vector<std::vector<uint32_t>> around_;
  SpatialGrid grid_{1.0};
};

}  // namespace

UntangleStats Untangle(SheetTriangles& st, std::vector<Vec3>& v,
                       const std::vector<uint8_t>& on_face, double max_move_voxels) {
  if (st.faces.empty() || max_move_voxels <= 0) return {};
  return Untangler(st, v, on_face, max_move_voxels).Run();
}

}  // namespace sheetmesh
