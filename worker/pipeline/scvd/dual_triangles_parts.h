// Internal to the dual triangulation (dual_triangles.cc and its parts): candidate
// triangles from the SCVD's blocks (dual_candidates.cc), the greedy face selection
// (face_selector.cc) and the rim strip and crack closing (rim_strip.cc).
#ifndef SHEETMESH_WORKER_PIPELINE_SCVD_DUAL_TRIANGLES_PARTS_H_
#define SHEETMESH_WORKER_PIPELINE_SCVD_DUAL_TRIANGLES_PARTS_H_

#include <algorithm>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "absl/container/inlined_vector.h"
#include "worker/pipeline/mesh/spatial_grid.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/scvd/dual_triangle_types.h"
#include "worker/pipeline/scvd/scvd.h"

namespace sheetmesh {

// A candidate triangle over three generators.
struct Candidate {
  uint32_t a, b, c;  // sorted generator ids
  uint32_t amended;  // 1 if it came from an amended block
  bool operator<(const Candidate& o) const {
    if (a != o.a) return a < o.a;
    if (b != o.b) return b < o.b;
    if (c != o.c) return c < o.c;
    return amended < o.amended;
  }
  bool SameFace(const Candidate& o) const { return a == o.a && b == o.b && c == o.c; }
};

inline Candidate MakeCandidate(uint32_t x, uint32_t y, uint32_t z, uint32_t amended) {
  std::array<uint32_t, 3> t = {x, y, z};
  std::sort(t.begin(), t.end());
  return {t[0], t[1], t[2], amended};
}

inline uint64_t PairKey(uint32_t a, uint32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<uint64_t>(a) << 32) | b;
}

// Scans every 2x2x2 block (min corners from -1 to n-1, so that sheets on the box wall and
// one-voxel-thin sets have blocks) for three or more cells.
struct BlockScan {
  std::vector<Candidate> candidates;
  uint64_t three = 0, amended = 0, unresolved = 0;
};

// Scans the blocks whose min corner lies in slice z (planes lo and hi reused between
// calls) into `out`.
void ScanSlicePair(const VoxelSet& set, const Scvd& scvd, int64_t z, std::vector<uint32_t>* lo,
                   std::vector<uint32_t>* hi, const absl::flat_hash_set<uint64_t>& adjacency,
                   std::span<const Vec3> pos, BlockScan* out);

// Keeps faces that neither fold onto nor cut through the faces kept before them.
class FaceSelector {
 public:
  enum class Verdict { kKept, kDegenerate, kFold, kIntersection };

  FaceSelector(const std::vector<Vec3>* positions, double cell_size,
               const DualTriangleOptions& options)
      : pos_(positions), grid_(cell_size), options_(options) {}

  // Judges `f` against the faces kept so far, and keeps it when it passes.
  Verdict TryAdd(const Face& f);

  const std::vector<Face>& faces() const { return faces_; }
  // Faces on edge (a, b).
  const absl::InlinedVector<uint32_t, 2>* EdgeFaces(uint32_t a, uint32_t b) const {
    auto it = edge_faces_.find(PairKey(a, b));
    return it == edge_faces_.end() ? nullptr : &it->second;
  }

 private:
  const std::vector<Vec3>* pos_;
  SpatialGrid grid_;
  DualTriangleOptions options_;
  absl::flat_hash_map<uint64_t, absl::InlinedVector<uint32_t, 2>> edge_faces_;
  std::vector<Face> faces_;
  std::vector<Triangle> geom_;
  std::vector<uint64_t> stamp_;
  uint64_t mark_ = 0;
};

// Counts verdict `v` in `stats`.
void Count(FaceSelector::Verdict v, DualTriangleStats* stats);

// Rim vertices and the strip joining the mesh boundary to them (see DualTriangleOptions::rim).
void AddRim(const VoxelSet& set, const NeighborTable& neighbors,
            std::span<const uint16_t> thickness, const Scvd& scvd,
            const DualTriangleOptions& options, std::vector<Vec3>* pos, FaceSelector* selector,
            DualTriangulation* out);

// Closes cracks (see DualTriangleOptions::close_cracks), a few passes so that a notch
// closes ear by ear.
void CloseCracks(const VoxelSet& set, const DualTriangleOptions& options,
                 const std::vector<Vec3>& pos, FaceSelector* selector, DualTriangulation* out);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SCVD_DUAL_TRIANGLES_PARTS_H_
