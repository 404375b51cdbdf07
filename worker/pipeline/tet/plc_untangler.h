// The untangler of clashing sheet triangles (Untangle, plc_parts.h), shared by its two
// files: plc_untangle.cc (the rounds, moves, flips and patches) and plc_untangle_split.cc
// (the splits that make crossing sheets meet in an edge). Private to the PLC's files.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_PLC_UNTANGLER_H_
#define SHEETMESH_WORKER_PIPELINE_TET_PLC_UNTANGLER_H_

#include <algorithm>
#include <cstdint>
#include <vector>

#include "absl/container/flat_hash_set.h"
#include "worker/pipeline/mesh/spatial_grid.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/plc_parts.h"

namespace sheetmesh::untangle_internal {

constexpr double kMinMovedAngle = 1.0;    // degrees: a move may not make a sliver triangle
constexpr double kMinSplitAngle = 0.2;    // degrees: nor a split (its pieces are thin by nature)
constexpr double kMinSplitLength = 0.05;  // voxels: a split's new edges at least this long
// What neither moves, flips, splits nor patches mended at those bounds is split with thin
// pieces as a last resort: the sheets then meet in an edge where they cross, which TetGen
// can mesh (with small tetrahedra there), rather than the job being refused.
constexpr double kLastResortSplitAngle = 1e-3;
constexpr double kLastResortSplitLength = 1e-4;
constexpr int kMaxRounds = 12;
constexpr int kLastResortRounds = 8;

inline Triangle TriangleOf(const std::vector<Vec3>& v, const Face& f) {
  return {v[f[0]], v[f[1]], v[f[2]]};
}

class Untangler {
 public:
  Untangler(SheetTriangles& st, std::vector<Vec3>& v, const std::vector<uint8_t>& on_face,
            double max_move)
      : st_(st), v_(v), on_face_(on_face), base_move_(max_move), max_move_(max_move) {}

  UntangleStats Run();

 private:
  // The faces of each vertex, the face grid (boxes grown by what moves may add), the
  // original normals.
  void Index();

  // Whether the faces in `changed` (as they are now in v_/st_) clash with any face, or a
  // face of them is a sliver or faces away from `normals` (the sheet's side there).
  bool Clean(const std::vector<uint32_t>& changed, const std::vector<Vec3>& normals,
             const std::vector<uint8_t>& gone = {}, double min_angle = kMinMovedAngle,
             const std::vector<uint32_t>& origins = {});

  static uint64_t PairKey(uint32_t x, uint32_t y) {
    return (uint64_t{std::min(x, y)} << 32) | std::max(x, y);
  }

  // Moves one vertex of the pair so that neither of its faces clashes with anything.
  bool MoveAVertex(uint32_t a, uint32_t b, std::vector<uint8_t>* touched, UntangleStats* stats);

  // Flips an edge of the pair shared with one other face of its piece, where that leaves
  // no clash.
  bool FlipAnEdge(uint32_t a, uint32_t b, std::vector<uint8_t>* touched, UntangleStats* stats);

  // Two triangles that share one corner p and cross beyond it (their planes' line through p
  // runs inside both) meet along a segment p-q, q where the line leaves the first of them
  // (on its edge opposite p). Both are split there so that p-q is an edge of each: the one
  // left at q along its edge (with the triangle across that edge), the other at q along its
  // edge too, or around q where q lies inside it. They then meet in an edge, as crossing
  // sheets must in the PLC; the surface stays where it was.
  bool SplitAtCrossing(uint32_t a, uint32_t b, UntangleStats* stats);

  // Two triangles sharing no corner that cut through each other meet along a segment s-e
  // whose ends lie on edges of the one or the other. Each end is added to both: on an edge
  // (with the triangle across it) where it lies on one, else inside; s-e is then an edge of
  // both triangulations (the second end lands in a piece that has the first as a corner).
  bool SplitThroughCrossing(uint32_t a, uint32_t b, UntangleStats* stats);

  // Adds vertex q (already in v_) to the piece of `pieces` it lies in: on the piece's edge
  // (splitting the face across it too, which joins `pieces` when it is one of them) or
  // inside it. Records what changed. False where q lies in none.
  bool InsertPoint(uint32_t q, std::vector<uint32_t>* pieces, std::vector<uint32_t>* changed,
                   std::vector<uint32_t>* origin);

  // The face f came from before this split began: itself, unless it was made by it.
  static uint32_t OriginOf(uint32_t f, const std::vector<uint32_t>& changed,
                           const std::vector<uint32_t>& origin) {
    for (size_t i = 0; i < changed.size(); ++i) {
      if (changed[i] == f) return origin[i];
    }
    return f;
  }

  // Keeps a split whose faces `changed` (each from the face origin[i] of `saved`, on its
  // side) leave no clash, counting it; else puts the faces and vertices back as they were.
  bool KeepSplitOrUndo(const std::vector<uint32_t>& changed, const std::vector<uint32_t>& origin,
                       const std::vector<Face>& saved, size_t faces_before, size_t vertices_before,
                       UntangleStats* stats);

  void Undo(const std::vector<Face>& saved, size_t faces_before, size_t vertices_before);

  // Makes the splits SplitAtCrossing chose, keeping them where they leave no clash.
  bool Split(uint32_t f_edge, const Face& edge_split, uint32_t f_other, const Face& other,
             const Vec3& q, double u_other, UntangleStats* stats);

  // Replaces the faces around the pair (every face of one piece at a corner of a or b) by
  // a fan from one new vertex to the patch's outline, where the outline is one loop and
  // the fan clashes with nothing: the patch's surface is kept, its tangle gone.
  bool RetriangulatePatch(uint32_t a, uint32_t b, UntangleStats* stats);

  // Puts faces added since Index() into the grid.
  void GrowGrid(const std::vector<uint32_t>& faces);

  // Face f changed its corners from `old`: the vertex index follows.
  void Reindex(uint32_t f, const Face& old);

  SheetTriangles& st_;
  std::vector<Vec3>& v_;
  const std::vector<uint8_t>& on_face_;
  const double base_move_;
  double max_move_;
  std::vector<std::vector<uint32_t>> around_;
  SpatialGrid grid_{1.0};
  absl::flat_hash_set<uint64_t> clashing_;     // the round's clashing pairs, by PairKey
  uint64_t target_ = 0;                        // the pair being mended
  double min_split_angle_ = kMinSplitAngle;    // degrees, the least angle a split may make
  double min_split_length_ = kMinSplitLength;  // voxels
};

}  // namespace sheetmesh::untangle_internal

#endif  // SHEETMESH_WORKER_PIPELINE_TET_PLC_UNTANGLER_H_
