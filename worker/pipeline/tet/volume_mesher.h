// BuildVolumeMesh: the tetrahedral mesh of the rock block with the sheets as tagged
// internal faces (paper §2.3.1, Figs. 10 and 14): PLC, TetGen, a conformity check that
// every sheet triangle is made of tetrahedron faces, and the quality of Table 3.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESHER_H_
#define SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESHER_H_

#include <cstdint>
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
};

struct Conformity {
  uint64_t sheet_triangles = 0;   // in the PLC
  uint64_t conforming = 0;        // exactly covered by tetrahedron faces on them
  double worst_area_error = 0;    // relative, over all sheet triangles
  std::vector<uint32_t> missing;  // PLC sheet triangles not covered (first 20)
  uint64_t orphan_faces = 0;      // facet faces (box or sheet) that are no tetrahedron's face
};

struct VolumeMeshResult {
  TetMesh mesh;
  TetQuality quality;
  Conformity conformity;
  uint32_t snapped_vertices = 0;
  uint32_t snap_held_vertices = 0;  // PlcOptions::snap_clear_voxels
  uint32_t merged_vertices = 0;
  uint32_t dropped_triangles = 0;
  uint32_t repaired_triangles = 0;
  uint32_t flipped_edges = 0;     // sheet edges flipped for better triangles (PlcOptions)
  uint32_t dropped_caps = 0;      // flat rim triangles dropped
  uint32_t dropped_overlaps = 0;  // rim triangles dropped for lying on another sheet
  uint32_t closed_slits = 0;      // PlcOptions::cap_degrees
  uint32_t opened_wedges = 0;     // PlcOptions::wedge_degrees
  uint32_t box_points = 0;        // points seeded on the box surface (for -Y)
  uint32_t seed_points = 0;       // lattice points seeded off the sheets (PlcOptions)
  double lattice_spacing = 0;     // their spacing, physical units (0: none)
  double box_volume = 0;          // physical units^3
  double tetgen_seconds = 0;
  uint32_t rederived_facets = 0;  // sheet facets whose faces TetGen listed wrongly (taken
                                  // again from the tetrahedra)
  TetImproveReport improvement;
};

// Meshes the box of `dims` (placed by `placement`) with `sheets` (voxel index coordinates)
// as internal faces. kFailedPrecondition when sheet triangles intersect (naming them);
// kInternal when the output does not conform (naming the first sheet triangle not
// covered) or the tetrahedra do not fill the box; TetGen's errors pass through.
absl::StatusOr<VolumeMeshResult> BuildVolumeMesh(const TriangleMesh& sheets, const Dims& dims,
                                                 const Placement& placement,
                                                 const VolumeMeshOptions& options,
                                                 const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESHER_H_
