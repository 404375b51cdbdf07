// Topology of a triangle mesh: edges and their faces, manifoldness, boundary loops,
// connected parts, orientation, duplicate and degenerate faces, self-intersections.
#ifndef SHEETMESH_WORKER_PIPELINE_MESH_MESH_TOPOLOGY_H_
#define SHEETMESH_WORKER_PIPELINE_MESH_MESH_TOPOLOGY_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <utility>
#include <vector>

#include "worker/pipeline/mesh/triangle_mesh.h"

namespace sheetmesh {

// Every undirected edge with the faces that use it.
class EdgeIndex {
 public:
  explicit EdgeIndex(const TriangleMesh& mesh);

  struct Edge {
    uint32_t a, b;          // a < b
    uint32_t first, count;  // faces_[first .. first + count)
  };
  const std::vector<Edge>& edges() const { return edges_; }
  // Faces of edge e.
  const uint32_t* faces(const Edge& e) const { return faces_.data() + e.first; }
  // Index of edge (a, b) in edges(), or -1.
  int64_t Find(uint32_t a, uint32_t b) const;

 private:
  std::vector<Edge> edges_;
  std::vector<uint32_t> faces_;
};

struct TopologyReport {
  size_t vertices = 0;
  size_t faces = 0;
  size_t edges = 0;
  size_t boundary_edges = 0;      // used by one face
  size_t manifold_edges = 0;      // used by two faces
  size_t nonmanifold_edges = 0;   // used by three or more
  size_t duplicate_faces = 0;     // faces with the same vertex set as an earlier face
  size_t degenerate_faces = 0;    // repeated vertex or zero area
  size_t boundary_loops = 0;      // connected groups of boundary edges
  size_t connected_parts = 0;     // groups of faces connected through edges (not the
                                  // extraction's pieces: one piece may be several)
  size_t inconsistent_edges = 0;  // two-face edges walked in the same direction by both
  size_t unused_vertices = 0;
  std::vector<std::pair<uint32_t, uint32_t>> nonmanifold_edge_list;

  // The counts by name (not the edge list), for the report.
  nlohmann::json Fields() const;
};

TopologyReport AnalyzeTopology(const TriangleMesh& mesh);

// Flips faces so that the two faces of every manifold edge traverse it in opposite
// directions, piece by piece (a piece grows across manifold edges only). Returns the number
// of pieces that cannot be oriented (a Möbius band): those keep some inconsistent edges.
size_t OrientConsistently(TriangleMesh* mesh);

// Pairs of faces (f < g) that intersect other than along what they share: faces with no
// common vertex that intersect, faces with one common vertex that overlap beyond it, and
// faces with a common edge folded onto each other (dihedral angle below
// `fold_angle_degrees`). At most `max_pairs` pairs.
// Whether the triangles (p, a1, a2) and (p, b1, b2), sharing only p, share more than p: the
// line their planes meet in enters both of their angles at p on one side (a touch counts),
// or, in one plane, their angles overlap.
bool WedgesOverlap(const Vec3& p, const Vec3& a1, const Vec3& a2, const Vec3& b1, const Vec3& b2);

// Whether faces a and b of vertices v clash, by the rules FindSelfIntersections applies to
// each pair (none shared: they intersect; one shared vertex: they overlap beyond it; a
// shared edge: folded onto each other below fold_angle_degrees).
bool FacesClash(const std::vector<Vec3>& v, const Face& a, const Face& b,
                double fold_angle_degrees = 1.0);

std::vector<std::pair<uint32_t, uint32_t>> FindSelfIntersections(const TriangleMesh& mesh,
                                                                 size_t max_pairs = 1000,
                                                                 double fold_angle_degrees = 1.0);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_MESH_MESH_TOPOLOGY_H_
