// VertexFreedom: how each vertex of a mesh under improvement may move so that the domain
// and the sheets stay as they are. A box vertex keeps the coordinates that put it on its
// box faces; a sheet vertex TetGen added slides within the sheet triangle it lies inside
// (in a plane) or along the sheet edge it lies on (on a line). A PLC sheet vertex off the
// box may move within a ball of a given reach around where it began (half that where
// sheets meet): a bounded change of the sheet, for slivers its vertices pin; the PLC's
// other sheet vertices never move. Internal to the improvement.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_VERTEX_FREEDOM_H_
#define SHEETMESH_WORKER_PIPELINE_TET_VERTEX_FREEDOM_H_

#include <cstdint>
#include <vector>

#include "worker/pipeline/tet/tet_mesh.h"

namespace sheetmesh {

// Thread-compatible. Vertex ids are the mesh's; AddFree and the others follow the ids of
// vertices added to it.
class VertexFreedom {
 public:
  // Vertices [0, input_nodes) are the PLC's; the box is [lo, hi]; the mesh's faces with a
  // piece >= 0 are sheet faces. PLC sheet vertices move within `sheet_reach` (0: never;
  // half of it at a junction).
  VertexFreedom(const TetMesh& mesh, const Vec3& lo, const Vec3& hi, uint32_t input_nodes,
                double sheet_reach = 0);

  bool may_move(uint32_t v) const { return mask_[v] != 0 || slide_[v] != Slide::kNone; }
  // Whether v lies inside the rock, on no facet: free in every direction (it may go).
  bool interior(uint32_t v) const { return mask_[v] == 7 && slide_[v] == Slide::kNone; }
  // Whether v is a sheet vertex TetGen or the improvement added, sliding within its sheet
  // triangle or along its sheet edge: the sheets keep their shape without it.
  bool slides(uint32_t v) const { return slide_[v] == Slide::kPlane || slide_[v] == Slide::kLine; }
  // d restricted to the moves vertex v may make.
  Vec3 Constrain(uint32_t v, Vec3 d) const;
  // p put back exactly on v's plane or line (through its first position). Constrain alone
  // leaves rounding noise of the size of the move's discarded part, which can be large (an
  // optimal-Delaunay point far off a sheet), and it would add up over moves.
  Vec3 Place(uint32_t v, const Vec3& p) const;
  // Whether coordinate k of v can change at all (a partial derivative worth taking).
  bool Varies(uint32_t v, int k) const {
    return slide_[v] != Slide::kNone || (mask_[v] & (1 << k));
  }

  uint32_t movable() const;  // vertices that may move (sliding ones included)
  uint32_t sliding() const;  // sheet vertices that slide
  // Whether v is a PLC sheet vertex that may move within its ball (only for the worst of
  // its star: the caller decides when).
  bool in_ball(uint32_t v) const { return v < slide_.size() && slide_[v] == Slide::kBall; }
  // Where v began (its anchor).
  const Vec3& anchor(uint32_t v) const { return anchor_[v]; }
  uint32_t in_balls() const;  // PLC sheet vertices that may move within their ball
  // v moves no more within its ball (a face at v is split: its pieces must stay in one plane).
  void Freeze(uint32_t v) {
    if (in_ball(v)) slide_[v] = Slide::kNone;
  }

  // The next vertex, added at p: free; sliding in the plane of unit normal `normal`; or
  // sliding along the line of unit direction `dir`.
  void AddFree(const Vec3& p);
  void AddInPlane(const Vec3& p, const Vec3& normal);
  void AddOnLine(const Vec3& p, const Vec3& dir);
  // ... or on a box face across axis k (0, 1, 2), sliding in it as the box's vertices do.
  void AddOnBox(const Vec3& p, int k);

 private:
  // Either way a sliding vertex keeps the sheet's faces tiling the input triangles, as long
  // as no tetrahedron inverts, which every move checks.
  enum class Slide : uint8_t { kNone, kPlane, kLine, kBall };

  void ClassifySheetNodes(const TetMesh& mesh, uint32_t input_nodes,
                          const std::vector<uint8_t>& off_box);
  void ClassifyPlcSheetNodes(const TetMesh& mesh, uint32_t input_nodes,
                             const std::vector<uint8_t>& off_box);

  std::vector<uint8_t> mask_;     // per vertex: bit k set = coordinate k may change
  std::vector<Slide> slide_;      // per vertex: sheet vertices that may slide
  std::vector<Vec3> axis_;        // per vertex: the plane's normal or the line's direction
  std::vector<Vec3> anchor_;      // per sliding vertex: its position before any move
  double reach_ = 0;              // of a kBall vertex from its anchor
  std::vector<double> reach_of_;  // per kBall vertex: its own (shorter at a junction)
  static constexpr double kJunctionReach = 0.5;
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_VERTEX_FREEDOM_H_
