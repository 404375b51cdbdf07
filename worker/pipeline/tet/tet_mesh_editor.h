// TetMeshEditor: a tetrahedral mesh under improvement — each vertex's star, each
// tetrahedron's quality, the facets' faces that no edit may remove — and the two edits all
// the improvement's operations are made of: kill a tetrahedron, add one. Internal to the
// improvement (tet_improve.cc and the operations it drives).
#ifndef SHEETMESH_WORKER_PIPELINE_TET_TET_MESH_EDITOR_H_
#define SHEETMESH_WORKER_PIPELINE_TET_TET_MESH_EDITOR_H_

#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "worker/pipeline/tet/tet_mesh.h"

namespace sheetmesh {

inline constexpr double kRegularDihedral = 70.528779365509308;  // acos(1/3), degrees
inline constexpr double kGain = 1e-6;  // degrees: the least rise that counts as an improvement

inline bool Has(const Tet& t, uint32_t v) {
  return t[0] == v || t[1] == v || t[2] == v || t[3] == v;
}

// Holds a reference to the mesh, which must outlive it; killed tetrahedra stay in its list
// (dead) until Finish. Quality is the smallest dihedral angle in degrees. Thread-compatible;
// its const methods may be called from several threads at once.
class TetMeshEditor {
 public:
  // REQUIRES: every tetrahedron of `mesh` is positively oriented.
  explicit TetMeshEditor(TetMesh* mesh);

  TetMesh& mesh() { return m_; }
  const TetMesh& mesh() const { return m_; }
  const Vec3& P(uint32_t v) const { return m_.nodes[v]; }
  // The vertex's position, to move it (the caller keeps qualities up to date).
  Vec3& node(uint32_t v) { return m_.nodes[v]; }
  uint32_t num_nodes() const { return static_cast<uint32_t>(m_.nodes.size()); }
  // A new vertex at p, in no tetrahedron yet; returns its id.
  uint32_t AddNode(const Vec3& p);

  const Tet& tet(uint32_t t) const { return m_.tets[t]; }
  bool alive(uint32_t t) const { return !dead_[t]; }
  // The number of live tetrahedra.
  uint64_t live() const { return m_.tets.size() - free_.size(); }
  double quality(uint32_t t) const { return q_[t]; }
  // Measures t again after its vertices moved, and clears its failed mark.
  void Remeasure(uint32_t t);
  // Whether an insertion was tried at t and failed since t last changed.
  bool failed(uint32_t t) const { return failed_[t]; }
  void set_failed(uint32_t t) { failed_[t] = 1; }
  // Forgets every failed insertion (when the insertion may do more than it could).
  void ClearFailed() { std::fill(failed_.begin(), failed_.end(), 0); }
  const std::vector<uint32_t>& star(uint32_t v) const { return star_[v]; }
  double Quality(const Tet& t) const;

  // Removes t (its slot is reused by a later Add); adds a tetrahedron.
  void Kill(uint32_t t);
  void Add(const Tet& tet);

  // The facets' faces (box and sheets): no edit may remove one.
  bool IsFacetFace(const FaceKey& face) const { return constrained_.contains(face); }
  // Index in mesh().faces of a facet face, or nullptr.
  const uint32_t* FacetFaceIndex(const FaceKey& face) const;
  void EraseFacetFace(const FaceKey& face) { constrained_.erase(face); }
  void SetFacetFace(const FaceKey& face, uint32_t index) { constrained_[face] = index; }
  // The sheet faces (indices into mesh().faces) at vertex v.
  std::vector<uint32_t>& sheet_faces_of(uint32_t v) { return sheet_faces_of_[v]; }
  const std::vector<uint32_t>& sheet_faces_of(uint32_t v) const { return sheet_faces_of_[v]; }
  // Sheet vertex v merged into w (an edge contraction along the sheets): a sheet face
  // holding both goes, every other one at v takes w for v. Faces that went leave
  // mesh().faces at Finish. REQUIRES: v on no box face.
  void ContractSheetFaces(uint32_t v, uint32_t w);

  // The tetrahedron sharing face f (opposite tet[f]) of t, or UINT32_MAX on the boundary.
  // Remembered once found: a remembered neighbour is checked (alive, holding the face) and
  // looked up again in the star only when an edit replaced it.
  uint32_t Neighbor(uint32_t t, int f) const;
  // Face f of t oriented so that the tetrahedron's inside is on its positive side.
  std::array<uint32_t, 3> InwardFace(uint32_t t, int f) const;

  // The smallest and mean quality of the live tetrahedra.
  std::pair<double, double> MinMean() const;
  // Live tetrahedra below `target`, worst first.
  std::vector<uint32_t> Bad(double target) const;
  // The worst quality of v's star.
  double StarMin(uint32_t v) const;

  // A clock of the edits: every Kill, Add and Remeasure ticks it and stamps the corners of
  // its tetrahedron. What a flip at t or a move of v looks at lies in the stars of t's
  // corners or of v (a vertex of the star moving remeasures the star's tetrahedra there),
  // so one that failed at clock() == s fails again while no such stamp is past s: the
  // work list of the improvement skips those.
  uint64_t clock() const { return clock_; }
  bool UnchangedSince(uint32_t v, uint64_t s) const { return changed_[v] <= s; }
  bool UnchangedSince(const Tet& t, uint64_t s) const {
    return changed_[t[0]] <= s && changed_[t[1]] <= s && changed_[t[2]] <= s && changed_[t[3]] <= s;
  }

  // Writes the live tetrahedra and facet faces back into the mesh, in order.
  void Finish();

 private:
  TetMesh& m_;
  std::vector<std::vector<uint32_t>> star_;  // vertex -> live tetrahedra
  std::vector<double> q_;                    // per tetrahedron: smallest dihedral angle
  std::vector<uint8_t> dead_;
  std::vector<uint8_t> failed_;  // per tetrahedron: insertion tried and failed, unchanged since
  std::vector<uint32_t> free_;   // dead slots to reuse
  uint64_t clock_ = 1;
  std::vector<uint64_t> changed_;  // per vertex: clock() at the last edit of its star
  void Stamp(const Tet& t) {
    ++clock_;
    for (uint32_t v : t) changed_[v] = clock_;
  }
  // Per tetrahedron and face: the neighbour last found there (kUnknown: none yet). A face
  // shared by two live tetrahedra has no third, so a remembered one that is alive and
  // holds the face is the neighbour.
  static constexpr uint32_t kUnknown = UINT32_MAX;
  mutable std::vector<std::array<uint32_t, 4>> neighbor_;
  absl::flat_hash_map<FaceKey, uint32_t> constrained_;  // facets' faces -> index in m_.faces
  std::vector<std::vector<uint32_t>> sheet_faces_of_;   // vertex -> its sheet faces
  std::vector<uint8_t> face_gone_;                      // per face: contracted away
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_TET_MESH_EDITOR_H_
