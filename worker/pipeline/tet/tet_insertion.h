// Vertex insertion for the improvement of a tetrahedral mesh: a new vertex off a sliver
// that the flips cannot mend, inserted into a star-shaped cavity that never crosses a
// facet; or, for the few slivers whose corners the sheets pin, a new vertex on a sheet
// face or sheet edge beside it, splitting that face in three or the faces on that edge in
// two, each piece keeping its input triangle, piece and thickness. Internal to the
// improvement.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_TET_INSERTION_H_
#define SHEETMESH_WORKER_PIPELINE_TET_TET_INSERTION_H_

#include <array>
#include <cstdint>
#include <vector>

#include "absl/container/flat_hash_set.h"
#include "worker/pipeline/tet/tet_improve_options.h"
#include "worker/pipeline/tet/tet_mesh_editor.h"
#include "worker/pipeline/tet/tet_smoothing.h"
#include "worker/pipeline/tet/vertex_freedom.h"

namespace sheetmesh {

// Holds references to the editor and the freedom, which must outlive it and which it
// extends with every vertex it inserts. Thread-compatible.
class VertexInserter {
 public:
  VertexInserter(TetMeshEditor& ed, VertexFreedom& fr, const TetImproveOptions& options)
      : ed_(ed),
        fr_(fr),
        options_(options),
        smoothing_{options.smoothing_floor_degrees, options.radius_weight} {}

  // Inserts a new vertex off the sliver t, on one side of its plane, into the cavity of
  // the tetrahedra around it, then smooths it. Kept (true) only if the cavity's worst
  // tetrahedron improves. A sliver whose corners have not moved since its last failed try
  // is not tried again.
  bool InsertNear(uint32_t t);

  // Whether a new vertex may go on a sheet face or edge (where no point off them will do).
  // Allowing them forgets the insertions that failed without them.
  void AllowSheetSplits(bool allow) {
    if (allow && !sheet_splits_) ed_.ClearFailed();
    sheet_splits_ = allow;
  }

  uint64_t facet_splits() const { return facet_splits_; }  // new vertices on sheet faces
  uint64_t edge_splits() const { return edge_splits_; }    // on sheet edges
  uint64_t box_splits() const { return box_splits_; }      // on box faces

 private:
  // A candidate new vertex: its cavity and fill; for a point on a sheet, the sheet faces it
  // splits (indices into the mesh's faces) and, on a sheet edge, that edge.
  struct Candidate {
    Vec3 p;
    std::vector<uint32_t> cavity;
    std::vector<Tet> fill;
    double quality = -1e300;  // the fill's worst tetrahedron
    std::vector<uint32_t> split;
    std::array<uint32_t, 2> edge = {UINT32_MAX, UINT32_MAX};
  };

  // The best point on a sheet face or sheet edge of, or next to, sliver t: inside each sheet
  // face holding an edge of t, a grid of ten points and the feet of t's other corners; on
  // each sheet edge of t (not on the box), five points along it and the feet of t's other
  // two corners. The cavity must hold t.
  // Such a point splits the face (into three) or every face on the edge (each into two), so
  // the sheet faces still tile the input triangles.
  Candidate BestSheetSplit(uint32_t t) const;
  // Candidates inside the sheet faces holding an edge of t, and on the sheet edges of t;
  // each kept in *best when it beats it.
  void SplitFaceCandidates(uint32_t t, Candidate* best) const;
  void SplitEdgeCandidates(uint32_t t, Candidate* best) const;
  // The cavity and fill of candidate c, grown from `seeds` across the `opened` facets; c
  // replaces *best when its fill's worst tetrahedron is better and every split face's
  // pieces are faces of the fill.
  void ConsiderSplit(Candidate c, const std::vector<uint32_t>& seeds,
                     const absl::flat_hash_set<FaceKey>& opened, Candidate* best) const;
  // Inserts the candidate's vertex: its cavity's tetrahedra replaced by the fill; on a
  // sheet, each split face replaced by its pieces (same input triangle, piece and
  // thickness, same orientation) and the vertex free to slide in that face or edge.
  void Apply(const Candidate& c);

  TetMeshEditor& ed_;
  VertexFreedom& fr_;
  const TetImproveOptions options_;
  bool sheet_splits_ = true;
  const SmoothingOptions smoothing_;
  uint64_t facet_splits_ = 0, edge_splits_ = 0, box_splits_ = 0;
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_TET_INSERTION_H_
