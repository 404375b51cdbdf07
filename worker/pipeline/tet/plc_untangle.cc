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

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/mesh/spatial_grid.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/plc_parts.h"
#include "worker/pipeline/tet/plc_untangler.h"

namespace sheetmesh {
namespace untangle_internal {

UntangleStats Untangler::Run() {
  UntangleStats stats;
  for (int round = 0; round < kMaxRounds + 2 + kLastResortRounds; ++round) {
    TriangleMesh mesh;
    mesh.vertices = v_;
    mesh.faces = st_.faces;
    const auto pairs = FindSelfIntersections(mesh, 100000, 1.0);
    stats.remaining_pairs = static_cast<uint32_t>(pairs.size());
    if (round == 0) stats.found_pairs = stats.remaining_pairs;
    if (pairs.empty()) break;
    Index();
    clashing_.clear();
    for (const auto& [a, b] : pairs) clashing_.insert(PairKey(a, b));
    std::vector<uint8_t> touched(st_.faces.size(), 0);
    uint32_t mended = 0;
    for (const auto& [a, b] : pairs) {
      if (touched[a] || touched[b]) continue;
      target_ = PairKey(a, b);
      if (MoveAVertex(a, b, &touched, &stats) || FlipAnEdge(a, b, &touched, &stats)) {
        ++mended;
      } else if (SplitAtCrossing(a, b, &stats) || SplitThroughCrossing(a, b, &stats)) {
        ++mended;
        break;  // the faces and their index changed: the next round looks again
      } else if (max_move_ >= 3 * base_move_ && RetriangulatePatch(a, b, &stats)) {
        ++mended;
        break;  // the faces and their index changed: the next round looks again
      }
    }
    if (mended == 0) {
      // What small moves cannot mend may need a larger one: up to three times the cap,
      // after everything else has been tried at the smaller; then thin splits.
      if (max_move_ < 3 * base_move_) {
        max_move_ += base_move_;
      } else if (min_split_angle_ > kLastResortSplitAngle) {
        min_split_angle_ = kLastResortSplitAngle;
        min_split_length_ = kLastResortSplitLength;
      } else {
        break;
      }
    }
  }
  return stats;
}

// The faces of each vertex, the face grid (boxes grown by what moves may add), the
// original normals.
void Untangler::Index() {
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
bool Untangler::Clean(const std::vector<uint32_t>& changed, const std::vector<Vec3>& normals,
                      const std::vector<uint8_t>& gone, double min_angle,
                      const std::vector<uint32_t>& origins) {
  absl::flat_hash_map<uint32_t, uint32_t> origin_of;  // changed face -> the face it was
  for (size_t i = 0; i < changed.size(); ++i) {
    origin_of[changed[i]] = origins.empty() ? changed[i] : origins[i];
  }
  for (size_t i = 0; i < changed.size(); ++i) {
    const Face& f = st_.faces[changed[i]];
    const Triangle t = TriangleOf(v_, f);
    if (MinAngleDegrees(t) < min_angle) return false;
    if (Dot(UnitNormal(t), normals[i]) <= 0) return false;
    Vec3 lo, hi;
    TriangleBox(t, 0.0, &lo, &hi);
    bool clash = false;
    const uint32_t of = origin_of[changed[i]];
    grid_.Query(lo, hi, [&](uint32_t g) {
      if (clash || g == changed[i]) return;
      const auto own = origin_of.find(g);
      if (own != origin_of.end() && g < changed[i]) return;  // that pair was looked at
      if (g < gone.size() && gone[g]) return;
      if (!FacesClash(v_, f, st_.faces[g], 1.0)) return;
      // A clash the faces they came from had already is another pair's to mend; the
      // pair being mended, or a new clash, is not allowed.
      const uint32_t og = own != origin_of.end() ? own->second : g;
      clash = PairKey(of, og) == target_ || !clashing_.contains(PairKey(of, og));
    });
    if (clash) return false;
  }
  return true;
}

// Moves one vertex of the pair so that neither of its faces clashes with anything.
bool Untangler::MoveAVertex(uint32_t a, uint32_t b, std::vector<uint8_t>* touched,
                            UntangleStats* stats) {
  std::vector<uint32_t> corners;
  for (uint32_t f : {a, b}) {
    for (uint32_t u : st_.faces[f]) {
      if (std::find(corners.begin(), corners.end(), u) == corners.end()) corners.push_back(u);
    }
  }
  for (uint32_t u : corners) {
    // A point the splits added (past on_face_) lies off the box faces.
    const uint8_t faces_on = u < on_face_.size() ? on_face_[u] : 0;
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
bool Untangler::FlipAnEdge(uint32_t a, uint32_t b, std::vector<uint8_t>* touched,
                           UntangleStats* stats) {
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

// Replaces the faces around the pair (every face of one piece at a corner of a or b) by
// a fan from one new vertex to the patch's outline, where the outline is one loop and
// the fan clashes with nothing: the patch's surface is kept, its tangle gone.
bool Untangler::RetriangulatePatch(uint32_t a, uint32_t b, UntangleStats* stats) {
  for (uint32_t seed : {a, b}) {
    const int32_t piece = st_.piece[seed];
    std::vector<uint32_t> patch;
    for (uint32_t f : {a, b}) {
      if (st_.piece[f] != piece) continue;
      for (uint32_t u : st_.faces[f]) {
        for (uint32_t g : around_[u]) {
          if (st_.piece[g] == piece && std::find(patch.begin(), patch.end(), g) == patch.end()) {
            patch.push_back(g);
          }
        }
      }
    }
    // The outline: directed edges of the patch that no other patch face has reversed.
    std::vector<std::pair<uint32_t, uint32_t>> outline;
    for (uint32_t f : patch) {
      for (int k = 0; k < 3; ++k) {
        const uint32_t x = st_.faces[f][k], y = st_.faces[f][(k + 1) % 3];
        int uses = 0;
        for (uint32_t g : patch) {
          const Face& gf = st_.faces[g];
          for (int j = 0; j < 3; ++j) {
            const uint32_t p = gf[j], q = gf[(j + 1) % 3];
            uses += (p == x && q == y) || (p == y && q == x);
          }
        }
        if (uses == 1) outline.emplace_back(x, y);
      }
    }
    // One simple loop, in order.
    std::vector<uint32_t> loop;
    if (outline.size() < 3) continue;
    loop.push_back(outline[0].first);
    uint32_t at = outline[0].second;
    bool simple = true;
    while (at != loop[0] && simple) {
      int next = -1, count = 0;
      for (size_t e = 0; e < outline.size(); ++e) {
        if (outline[e].first == at) next = static_cast<int>(e), ++count;
      }
      simple = count == 1 && loop.size() < outline.size();
      if (!simple) break;
      loop.push_back(at);
      at = outline[next].second;
    }
    if (!simple || loop.size() != outline.size()) continue;
    // The patch's side, thickness and place.
    Vec3 side(0, 0, 0), middle(0, 0, 0);
    double area = 0, thick = 0;
    for (uint32_t f : patch) {
      const Triangle t = TriangleOf(v_, st_.faces[f]);
      side = side + AreaVector(t);
      area += Area(t);
      thick += Area(t) * st_.thickness[f];
    }
    side = Normalized(side);
    for (uint32_t u : loop) middle = middle + v_[u];
    middle = middle * (1.0 / loop.size());
    const std::vector<Face> old_faces = [&] {
      std::vector<Face> o;
      for (uint32_t f : patch) o.push_back(st_.faces[f]);
      return o;
    }();
    const uint32_t centre = static_cast<uint32_t>(v_.size());
    v_.push_back(middle);
    std::vector<Face> fan;
    for (size_t k = 0; k < loop.size(); ++k) {
      fan.push_back({loop[k], loop[(k + 1) % loop.size()], centre});
    }
    // Patch faces first take the fan's faces; the rest of the fan is appended, the rest
    // of the patch removed at the end.
    std::vector<uint32_t> changed;
    const size_t keep = std::min(patch.size(), fan.size());
    for (size_t k = 0; k < keep; ++k) st_.faces[patch[k]] = fan[k], changed.push_back(patch[k]);
    const size_t before = st_.faces.size();
    for (size_t k = keep; k < fan.size(); ++k) {
      st_.faces.push_back(fan[k]);
      st_.source.push_back(st_.source[patch[0]]);
      st_.piece.push_back(piece);
      st_.thickness.push_back(st_.thickness[patch[0]]);
      changed.push_back(static_cast<uint32_t>(st_.faces.size() - 1));
    }
    std::vector<uint8_t> gone(st_.faces.size(), 0);
    for (size_t k = keep; k < patch.size(); ++k) gone[patch[k]] = 1;
    // A removed face must not count as a clash partner: it becomes the centre alone.
    for (size_t k = keep; k < patch.size(); ++k) st_.faces[patch[k]] = {centre, centre, centre};
    GrowGrid(changed);
    const std::vector<Vec3> normals(changed.size(), side);
    if (Clean(changed, normals, gone)) {
      for (uint32_t f : changed) st_.thickness[f] = static_cast<float>(thick / area);
      st_ = Without(st_, gone);
      ++stats->retriangulated_patches;
      return true;
    }
    // Undone.
    for (size_t k = 0; k < patch.size(); ++k) st_.faces[patch[k]] = old_faces[k];
    st_.faces.resize(before);
    st_.source.resize(before);
    st_.piece.resize(before);
    st_.thickness.resize(before);
    v_.pop_back();
  }
  return false;
}

// Puts faces added since Index() into the grid.
void Untangler::GrowGrid(const std::vector<uint32_t>& faces) {
  for (uint32_t f : faces) {
    Vec3 lo, hi;
    TriangleBox(TriangleOf(v_, st_.faces[f]), 2 * max_move_, &lo, &hi);
    grid_.Insert(f, lo, hi);
  }
}

// Face f changed its corners from `old`: the vertex index follows.
void Untangler::Reindex(uint32_t f, const Face& old) {
  for (uint32_t u : old) {
    auto& list = around_[u];
    list.erase(std::remove(list.begin(), list.end(), f), list.end());
  }
  for (uint32_t u : st_.faces[f]) around_[u].push_back(f);
}

}  // namespace untangle_internal

UntangleStats Untangle(SheetTriangles& st, std::vector<Vec3>& v,
                       const std::vector<uint8_t>& on_face, double max_move_voxels) {
  if (st.faces.empty() || max_move_voxels <= 0) return {};
  return untangle_internal::Untangler(st, v, on_face, max_move_voxels).Run();
}

}  // namespace sheetmesh
