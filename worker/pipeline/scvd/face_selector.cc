#include <algorithm>

#include "worker/pipeline/scvd/dual_triangles_parts.h"

namespace sheetmesh {
namespace {

struct Box {
  Vec3 lo, hi;
};

Box BoundsOf(const Triangle& t) {
  Box b;
  b.lo = {std::min({t[0].x, t[1].x, t[2].x}), std::min({t[0].y, t[1].y, t[2].y}),
          std::min({t[0].z, t[1].z, t[2].z})};
  b.hi = {std::max({t[0].x, t[1].x, t[2].x}), std::max({t[0].y, t[1].y, t[2].y}),
          std::max({t[0].z, t[1].z, t[2].z})};
  return b;
}

}  // namespace

FaceSelector::Verdict FaceSelector::TryAdd(const Face& f) {
  const std::vector<Vec3>& pos = *pos_;
  const Triangle t = {pos[f[0]], pos[f[1]], pos[f[2]]};
  const double longest = std::max({Norm2(t[1] - t[0]), Norm2(t[2] - t[1]), Norm2(t[0] - t[2])});
  if (!(Norm(AreaVector(t)) > 1e-6 * longest) || MinAngleDegrees(t) < 0.5) {
    return Verdict::kDegenerate;
  }
  for (int k = 0; k < 3; ++k) {
    const uint32_t p = f[k], q = f[(k + 1) % 3], r = f[(k + 2) % 3];
    auto it = edge_faces_.find(PairKey(p, q));
    if (it == edge_faces_.end()) continue;
    for (uint32_t g : it->second) {
      const Face& h = faces_[g];
      const uint32_t s = h[0] != p && h[0] != q ? h[0] : (h[1] != p && h[1] != q ? h[1] : h[2]);
      if (s == r) return Verdict::kFold;  // the same triangle again
      if (DihedralAngleDegrees(pos[p], pos[q], pos[r], pos[s]) < options_.fold_angle_degrees) {
        return Verdict::kFold;
      }
    }
  }
  const Box box = BoundsOf(t);
  if (options_.reject_intersections) {
    bool hit = false;
    ++mark_;
    grid_.Query(box.lo, box.hi, [&](uint32_t g) {
      if (hit || stamp_[g] == mark_) return;
      stamp_[g] = mark_;
      const Face& h = faces_[g];
      int shared = 0;
      for (uint32_t u : f)
        for (uint32_t v : h) shared += u == v;
      if (shared >= 2) return;  // a shared edge was judged by the fold test
      hit = shared == 0 ? TrianglesIntersect(t, geom_[g])
                        : TrianglesIntersect(Shrink(t, 1e-3), Shrink(geom_[g], 1e-3));
    });
    if (hit) return Verdict::kIntersection;
  }
  const uint32_t id = static_cast<uint32_t>(faces_.size());
  faces_.push_back(f);
  geom_.push_back(t);
  stamp_.push_back(0);
  grid_.Insert(id, box.lo, box.hi);
  for (int k = 0; k < 3; ++k) edge_faces_[PairKey(f[k], f[(k + 1) % 3])].push_back(id);
  return Verdict::kKept;
}

void Count(FaceSelector::Verdict v, DualTriangleStats* stats) {
  switch (v) {
    case FaceSelector::Verdict::kKept:
      ++stats->kept;
      break;
    case FaceSelector::Verdict::kDegenerate:
      ++stats->rejected_degenerate;
      break;
    case FaceSelector::Verdict::kFold:
      ++stats->rejected_fold;
      break;
    case FaceSelector::Verdict::kIntersection:
      ++stats->rejected_intersection;
      break;
  }
}

}  // namespace sheetmesh
