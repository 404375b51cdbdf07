// BuildVolumeMesh: the tetrahedral mesh of the rock block with the sheets as tagged
// internal faces (paper §2.3.1, Figs. 10 and 14): PLC, TetGen, a conformity check that
// every sheet triangle is made of tetrahedron faces, and the quality of Table 3.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESHER_H_
#define SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESHER_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/tet/plc.h"
#include "worker/pipeline/tet/tet_improve.h"
#include "worker/pipeline/tet/tet_quality.h"
#include "worker/pipeline/tet/tetgen_runner.h"

namespace sheetmesh {

struct VolumeMeshOptions {
  PlcOptions plc;
  TetgenOptions tetgen;
  TetImproveOptions improve;  // the clean-up of TetGen's output
  // A solver's budget: the mesh has at most this many tetrahedra (0: no bound). Where
  // TetGen's mesh of the seeded PLC leaves the improvement too little room (it takes over
  // three quarters of it), the lattice is coarsened, by the prediction (6 tetrahedra per PLC
  // point) and then by TetGen's count, then goes (TetGen's own sizing gives the improvement
  // the best start), and last is 8 median edges; the improvement adds no more than the
  // budget allows. The least possible is TetGen's mesh at that coarsest lattice (or with
  // none, when plc.lattice is 0): a budget below it is kInvalidArgument naming it.
  uint64_t max_tetrahedra = 0;
  // Rounds of bisecting the sheet triangles around slivers they pin (RefineAtSlivers; 0:
  // none), each a TetGen run and an improvement of its own. Over the 140 runs of the volume
  // mesh sweep a third round was never kept (bench/RESULTS.md, issue 41). Users turn it off
  // with tet.min_dihedral = 0, its aim; tests of the steps before it turn it off here.
  int sliver_rounds = 2;
};

struct Conformity {
  uint64_t sheet_triangles = 0;   // in the PLC
  uint64_t conforming = 0;        // exactly covered by tetrahedron faces on them
  double worst_area_error = 0;    // relative, over all sheet triangles
  std::vector<uint32_t> missing;  // PLC sheet triangles not covered (first 20)
  uint64_t orphan_faces = 0;      // facet faces (box or sheet) that are no tetrahedron's face

  // sheet_triangles, conforming, worst_area_error, for the report.
  nlohmann::json Fields() const;
};

// Where the mesh's smallest dihedral angle is under the aim (tet.min_dihedral), so that it
// is never silent: the angle, the tetrahedron's centre and why it is left.
struct AngleWarning {
  double degrees = 0;         // the smallest dihedral angle
  double aim_degrees = 0;     // tet.min_dihedral
  Vec3 at;                    // the worst tetrahedron's centre, physical units
  Vec3 at_voxel;              // the same, in voxel indices (x, y, z)
  int corners_on_sheets = 0;  // of its 4 corners, on sheet faces
  std::string cause;          // why, in words, with what may help

  // "min dihedral 5.66° under tet.min_dihedral = 10° at voxel (51, 52, 30): CAUSE".
  std::string Line() const;
  nlohmann::json Fields() const;
};

// What the volume mesh is and how it was made: everything the report says of it. The PLC's
// own figures come first (PlcStats).
struct VolumeMeshStats : PlcStats {
  uint64_t nodes = 0;
  uint64_t tetrahedra = 0;
  uint64_t sheet_faces = 0;  // tetrahedron faces on the sheets (and the bodies' walls)
  // Each body's region: its tetrahedra and their volume (physical units^3). A body whose
  // walls the PLC's mends opened leaks into the rock and has none.
  struct BodyRegion {
    int32_t piece = 0;
    uint64_t tetrahedra = 0;
    double volume = 0;
  };
  std::vector<BodyRegion> bodies;
  // Formula 5 of the sheets as the volume mesh has them (its sheet faces and bodies' walls,
  // after the PLC's snaps and repairs), set by the pipeline: the surface the user gets in
  // the volume mesh, beside the score of the surface it was made from.
  std::optional<double> delivered_similarity;
  std::optional<AngleWarning> angle_warning;  // set where the minimum is under the aim
  double voxels_per_tet = 0;  // the box's voxels per tetrahedron (the paper's 1 : 6704)
  TetQuality quality;
  Conformity conformity;
  double box_volume = 0;        // physical units^3
  std::string tetgen_switches;  // as TetGen ran (the run that made the mesh)
  // TetGen runs that crashed or failed before the one that made the mesh: their switches
  // and errors (RunTetgenRecovering).
  std::vector<std::string> tetgen_recovery;
  double tetgen_seconds = 0;          // the last TetGen run's
  uint64_t tetgen_tetrahedra = 0;     // TetGen's, before the improvement
  uint64_t max_tetrahedra = 0;        // the budget asked for (0: none)
  uint64_t predicted_tetrahedra = 0;  // 6 per PLC point: TetGen's count on a lattice
  uint32_t sizing_predictions = 0;    // PLCs built to bring the prediction within a budget
  uint32_t sizing_attempts = 0;       // TetGen runs: more than one when the budget coarsened
                                      // the lattice
  double lattice = 0;                 // the lattice's spacing in median sheet edges, as used
  double grading = 0;                 // PlcOptions::grading, as used
  uint32_t rederived_facets = 0;      // sheet facets whose faces TetGen listed wrongly (taken
                                      // again from the tetrahedra)
  TetImproveReport improvement;
  // The PLC's narrowest wedges (MeasureWedges, under tet.min_dihedral): where the mesh's
  // smallest angle is at this bound, the input forces it.
  WedgeBound wedges;
  // The sheet triangles bisected around slivers the sheets pinned (RefineAtSlivers).
  struct SliverRefinement {
    double min_dihedral_before = 0;  // degrees, before any round
    uint32_t slivers_on_sheets = 0;  // tetrahedra under tet.min_dihedral with two or
                                     // more corners on the sheets, before any round
    uint32_t rounds = 0;             // rounds kept
    uint32_t split_edges = 0;        // sheet edges bisected in them
    std::string stopped;             // why a round was not kept, if one was not
  } sliver_refinement;

  // Every figure by name, the quality and conformity nested, for the report.
  nlohmann::json Fields() const;
};

struct VolumeMeshResult : VolumeMeshStats {
  TetMesh mesh;
};

// Meshes the box of `dims` (placed by `placement`) with `sheets` (voxel index coordinates)
// as internal faces; the pieces that are bodies (sheets.body_pieces) bound regions of
// their own (TetMesh::tet_region). Each sheet face carries its aperture (face_aperture_voxels, else
// face_thickness_voxels) as the volume mesh's face_thickness_voxels. kFailedPrecondition when sheet
// triangles intersect (naming them); kInternal when the output does not conform (naming the first
// sheet triangle not covered) or the tetrahedra do not fill the box; TetGen's errors pass through.
absl::StatusOr<VolumeMeshResult> BuildVolumeMesh(const TriangleMesh& sheets, const Dims& dims,
                                                 const Placement& placement,
                                                 const VolumeMeshOptions& options,
                                                 const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESHER_H_
