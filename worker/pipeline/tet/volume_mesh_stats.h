// What the volume mesh is and how it was made (VolumeMeshStats, its conformity and angle
// warning) and the mesh itself (VolumeMeshResult): the volume mesher's answer, apart from
// the mesher so that its checks (volume_mesh_checks.h) and the report (tet_report.cc) use
// it without the mesher.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESH_STATS_H_
#define SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESH_STATS_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "worker/pipeline/tet/plc.h"
#include "worker/pipeline/tet/tet_improve.h"
#include "worker/pipeline/tet/tet_quality.h"

namespace sheetmesh {

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
  uint32_t seed_moves = 0;         // times the lattice seeds (last, the sheet vertices) were moved
                                   // for TetGen to try again
  double tetgen_seconds = 0;       // the last TetGen run's
  uint64_t tetgen_tetrahedra = 0;  // TetGen's, before the improvement
  uint64_t max_tetrahedra = 0;     // the budget asked for (0: none)
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
  // Where the mesh stayed under tet.min_dihedral, TetGen, the improvement and the sliver
  // rounds ran once more from the lattice seeds moved; the better mesh was kept.
  struct SecondTry {
    bool tried = false;
    double min_dihedral_first = 0;   // degrees, the first mesh's
    double min_dihedral_second = 0;  // the second's (0: it did not finish)
    bool kept = false;               // the second mesh is the one written
    std::string stopped;             // why it did not finish, if it did not
  } second_try;

  // Every figure by name, the quality and conformity nested, for the report.
  nlohmann::json Fields() const;
};

struct VolumeMeshResult : VolumeMeshStats {
  TetMesh mesh;
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESH_STATS_H_
