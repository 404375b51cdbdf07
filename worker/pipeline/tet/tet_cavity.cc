#include "worker/pipeline/tet/tet_cavity.h"

#include <algorithm>

namespace sheetmesh {
namespace {

// A set of tetrahedron ids for one cavity: membership is a mark per id (this epoch's
// number), so a test costs no hashing and starting a new set costs nothing. Each thread
// keeps its own two (the cavity and the tetrahedra dropped from it).
class IdSet {
 public:
  void Clear() {
    members_.clear();
    size_ = 0;
    if (++epoch_ == 0) {  // wrapped: forget every old mark
      std::fill(mark_.begin(), mark_.end(), 0);
      epoch_ = 1;
    }
  }
  bool contains(uint32_t id) const { return id < mark_.size() && mark_[id] == epoch_; }
  size_t size() const { return size_; }
  void insert(uint32_t id) {
    if (id >= mark_.size()) mark_.resize(id + 1 + id / 4, 0);
    if (mark_[id] == epoch_) return;
    mark_[id] = epoch_;
    members_.push_back(id);
    ++size_;
  }
  void erase(uint32_t id) {
    if (!contains(id)) return;
    mark_[id] = 0;
    --size_;
  }
  // The members in increasing order (an erased id is left out, a re-inserted one counted
  // once).
  std::vector<uint32_t> Sorted() const {
    std::vector<uint32_t> v;
    v.reserve(members_.size());
    for (uint32_t id : members_) {
      if (contains(id)) v.push_back(id);
    }
    std::sort(v.begin(), v.end());
    v.erase(std::unique(v.begin(), v.end()), v.end());
    return v;
  }

 private:
  std::vector<uint32_t> mark_;
  std::vector<uint32_t> members_;  // every id inserted since Clear, erased ones too
  size_t size_ = 0;
  uint32_t epoch_ = 0;
};

// Whether `face` is a facet face the cavity may not cross (one the new vertex does not
// split).
bool Blocks(const TetMeshEditor& ed, const FaceKey& face,
            const absl::flat_hash_set<FaceKey>& opened) {
  return ed.IsFacetFace(face) && !opened.contains(face);
}

// Whether face f of cavity tetrahedron x bounds the cavity: its neighbour is outside, or
// it is a facet's face (the cavity can reach both sides of a sheet around its rim; such
// a face must stay, so it bounds the cavity on both sides and one side then fails to see
// the new vertex). Facets in `opened` are the ones the new vertex splits (a sheet's, or
// the box's): they do not bound the cavity.
bool OnCavityBoundary(const TetMeshEditor& ed, const IdSet& in, uint32_t x, int f,
                      const absl::flat_hash_set<FaceKey>& opened) {
  const uint32_t y = ed.Neighbor(x, f);
  // A box face the new vertex splits: its pieces are faces of the fill, not it.
  if (y == UINT32_MAX) return !opened.contains(TetFace(ed.tet(x), f));
  if (!in.contains(y)) return true;
  return Blocks(ed, TetFace(ed.tet(x), f), opened);
}

bool InCircumsphere(const TetMeshEditor& ed, const Tet& t, const Vec3& p) {
  Vec3 cc;
  return Circumcentre(ed.P(t[0]), ed.P(t[1]), ed.P(t[2]), ed.P(t[3]), &cc) &&
         Norm2(p - cc) < Norm2(ed.P(t[0]) - cc);
}

}  // namespace

bool Cavity(const TetMeshEditor& ed, uint32_t t, const Vec3& p, std::vector<uint32_t>* cavity,
            std::vector<Tet>* fill) {
  constexpr int kMaxWalk = 64;
  // Walk from t to the tetrahedron holding p.
  uint32_t at = t;
  for (int step = 0;; ++step) {
    if (step == kMaxWalk) return false;
    // Leave through the face p is farthest behind, but never through a facet.
    int exit = -1;
    bool behind_facet = false;
    double most = 0;
    for (int f = 0; f < 4; ++f) {
      const auto face = ed.InwardFace(at, f);
      const double side = TetVolume(ed.P(face[0]), ed.P(face[1]), ed.P(face[2]), p);
      if (side >= 0) continue;
      if (ed.IsFacetFace(SortedFace(face[0], face[1], face[2]))) {
        behind_facet = true;
      } else if (side < most) {
        most = side;
        exit = f;
      }
    }
    if (exit < 0) {
      if (behind_facet) return false;
      break;
    }
    at = ed.Neighbor(at, exit);
    if (at == UINT32_MAX) return false;
  }
  return GrowCavity(ed, p, {at, t}, {}, {}, cavity, fill);
}

bool GrowCavity(const TetMeshEditor& ed, const Vec3& p, const std::vector<uint32_t>& seeds,
                const absl::flat_hash_set<FaceKey>& opened,
                const std::vector<std::pair<uint32_t, uint32_t>>& keep,
                std::vector<uint32_t>* cavity, std::vector<Tet>* fill) {
  constexpr size_t kMaxCavity = 128;
  thread_local IdSet in, dropped;
  in.Clear();
  dropped.Clear();
  for (uint32_t s : seeds) in.insert(s);
  std::vector<uint32_t> queue(seeds.begin(), seeds.end());
  while (!queue.empty() && in.size() < kMaxCavity) {
    const uint32_t x = queue.back();
    queue.pop_back();
    for (int f = 0; f < 4; ++f) {
      if (Blocks(ed, TetFace(ed.tet(x), f), opened)) continue;
      const uint32_t y = ed.Neighbor(x, f);
      if (y == UINT32_MAX || in.contains(y) || !InCircumsphere(ed, ed.tet(y), p)) continue;
      in.insert(y);
      queue.push_back(y);
    }
  }
  // Make every boundary face see p, growing across it where allowed, else dropping its
  // owner; then drop tetrahedra until no vertex is inside the cavity (it would be lost).
  // A dropped tetrahedron never comes back, so this ends.
  auto drop = [&](uint32_t x) {
    if (std::find(seeds.begin(), seeds.end(), x) != seeds.end()) return false;
    in.erase(x);
    dropped.insert(x);
    return true;
  };
  for (int round = 0;; ++round) {
    if (round == 64 || in.size() > kMaxCavity) return false;
    std::vector<std::pair<uint32_t, int>> hidden;
    for (uint32_t x : in.Sorted()) {
      for (int f = 0; f < 4; ++f) {
        if (!OnCavityBoundary(ed, in, x, f, opened)) continue;
        const auto face = ed.InwardFace(x, f);
        if (!(TetVolume(ed.P(face[0]), ed.P(face[1]), ed.P(face[2]), p) > 0))
          hidden.push_back({x, f});
      }
    }
    for (const auto& [x, f] : hidden) {
      if (!in.contains(x)) continue;
      const uint32_t y = ed.Neighbor(x, f);
      if (y != UINT32_MAX && !dropped.contains(y) && !Blocks(ed, TetFace(ed.tet(x), f), opened)) {
        in.insert(y);
      } else if (!drop(x)) {
        return false;
      }
    }
    if (!hidden.empty()) continue;
    bool inside = false;
    for (uint32_t x : in.Sorted()) {
      for (uint32_t w : ed.tet(x)) {
        if (!in.contains(x)) break;
        const bool all_in = std::all_of(ed.star(w).begin(), ed.star(w).end(),
                                        [&](uint32_t s) { return in.contains(s); });
        if (!all_in) continue;
        inside = true;
        bool any = false;
        for (uint32_t s : ed.star(w)) {
          if (drop(s)) {
            any = true;
            break;
          }
        }
        if (!any) return false;
      }
    }
    for (const auto& [u, w] : keep) {
      std::vector<uint32_t> around;
      for (uint32_t s : ed.star(u)) {
        if (Has(ed.tet(s), w)) around.push_back(s);
      }
      if (!std::all_of(around.begin(), around.end(), [&](uint32_t s) { return in.contains(s); })) {
        continue;
      }
      inside = true;
      if (std::none_of(around.begin(), around.end(), drop)) return false;
    }
    if (!inside) break;
  }
  // Fill: p joined to every boundary face; every vertex of the cavity must stay on it.
  *cavity = in.Sorted();
  fill->clear();
  absl::flat_hash_set<uint32_t> on_boundary, all;
  for (uint32_t x : *cavity) {
    for (int f = 0; f < 4; ++f) {
      all.insert(ed.tet(x)[f]);
      if (!OnCavityBoundary(ed, in, x, f, opened)) continue;
      const auto face = ed.InwardFace(x, f);
      // Inward face (f0, f1, f2) with p on its positive side: (f0, f1, f2, p) is positive.
      fill->push_back({face[0], face[1], face[2], UINT32_MAX});
      on_boundary.insert(face.begin(), face.end());
    }
  }
  return all.size() == on_boundary.size();
}

}  // namespace sheetmesh
