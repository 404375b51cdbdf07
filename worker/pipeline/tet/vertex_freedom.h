// VertexFreedom: how each vertex of a mesh under improvement may move so that the domain
// and the sheets stay as they are. PLC vertices on a sheet never move; a box vertex keeps
// the coordinates that put it on its box faces; a sheet vertex TetGen added slides within
// the sheet triangle it lies inside (in a plane) or along the sheet edge it lies on (on a
// line). Internal to the improvement.
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
  // piece >= 0 are sheet faces.
  VertexFreedom(const TetMesh& mesh, const Vec3& lo, const Vec3& hi, uint32_t input_nodes);

  bool may_move(uint32_t v) const { return mask_[v] != 0 || slide_[v] != Slide::kNone; }
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

  // The next vertex, added at p: free; sliding in the plane of unit normal `normal`; or
  // sliding along the line of unit direction `dir`.
  void AddFree(const Vec3& p);
  void AddInPlane(const Vec3& p, const Vec3& normal);
  void AddOnLine(const Vec3& p, const Vec3& dir);

 private:
  // Either way a sliding vertex keeps the sheet's faces tiling the input triangles, as long
  // as no tetrahedron inverts, which every move checks.
  enum class Slide : uint8_t { kNone, kPlane, kLine };

  void ClassifySheetNodes(const TetMesh& mesh, uint32_t input_nodes,
                          const std::vector<uint8_t>& off_box);

  std::vector<uint8_t> mask_;  // per vertex: bit k set = coordinate k may change
  std::vector<Slide> slide_;   // per vertex: sheet vertices that may slide
  std::vector<Vec3> axis_;     // per vertex: the plane's normal or the line's direction
  std::vector<Vec3> anchor_;   // per sliding vertex: its position before any move
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_VERTEX_FREEDOM_H_
