// BuildSurface: the surface mesh of a sheet set (paper §2.3.1, ALGORITHM §8): SCVD with
// radius r, dual triangles, then per-face thickness and piece.
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_SURFACE_BUILDER_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_SURFACE_BUILDER_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/mesh/decimate.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/scvd/dual_triangles.h"
#include "worker/pipeline/scvd/scvd.h"
#include "worker/pipeline/similarity/face_attributes.h"
#include "worker/pipeline/surface/face_apertures.h"
#include "worker/pipeline/surface/surface_options.h"
#include "worker/pipeline/surface/vertex_fit.h"
#include "worker/pipeline/voxel/sheet_analysis.h"

namespace sheetmesh {

// What error-driven sizing did: both surfaces' formula-5 scores and which was kept.
struct ErrorDensityStats {
  double plain_similarity = 0;
  double weighted_similarity = 0;
  bool kept_weighted = false;
};

// What surface.mesher auto did: both surfaces' formula-5 scores and which was kept.
struct MesherChoiceStats {
  double scvd_similarity = 0;
  double mid_similarity = 0;
  bool kept_mid = false;
  double margin = 0;  // the mid-surface is kept down to this much below the SCVD's score
};

// A component that gave no triangle: too small for three cells at this r.
struct SkippedComponent {
  uint32_t component = 0;
  uint64_t voxels = 0;
};

struct SurfaceResult {
  TriangleMesh mesh;  // face_thickness_voxels, face_piece, vertex_thickness_voxels set
  std::vector<uint32_t> vertex_generator;          // SCVD generator of each vertex of the dual mesh
                                                   // (before any decimation)
  std::optional<DecimateStats> decimation;         // when triangles decimated the mesh
  std::optional<VertexFitStats> vertex_fit;        // when fit_vertices moved the vertices
  std::optional<FaceApertureStats> apertures;      // when fit_walls fitted the heights
  size_t smoothed_vertices = 0;                    // vertices the thick-sheet smoothing moved
  std::optional<ErrorDensityStats> error_density;  // when options.error_density was > 0
  std::optional<MesherChoiceStats> mesher_choice;  // with surface.mesher auto
  Scvd scvd;
  DualTriangleStats triangle_stats;
  // With bricks: how many held sheet, the halo used, seam faces or vertices the bricks
  // did not build alike (0 unless the halo's retries ran out).
  uint64_t bricks = 0;
  int brick_halo = 0;
  uint64_t seam_mismatches = 0;
  uint32_t components = 0;          // 6-connected components of the sheet
  uint32_t skipped_components = 0;  // of those, components with no triangle
  uint64_t skipped_voxels = 0;
  std::vector<SkippedComponent> largest_skipped;  // up to 20, largest first
  double scvd_seconds = 0;
  double triangles_seconds = 0;
  double attributes_seconds = 0;
};

// What the surface is, for the report: the SCVD's figures, the mesh's counts and sizes,
// how its triangles were chosen and its topology.
struct SurfaceStats {
  uint32_t generators = 0;
  int lloyd_iterations = 0;
  bool lloyd_converged = false;
  double energy = 0;  // E of the last growth
  uint64_t vertices = 0;
  uint64_t triangles = 0;
  double element_size_voxels = 0;  // mean edge length
  double element_size = 0;         // the same, physical units
  double area_voxels = 0;
  DualTriangleStats triangle_stats;
  TopologyReport topology;          // without the edge list
  uint32_t skipped_components = 0;  // components too small for a triangle
  uint64_t skipped_voxels = 0;
  uint64_t bricks = 0;  // with surface.bricks: bricks that held sheet, their halo, and
  int brick_halo = 0;   // seam faces or vertices they did not build alike
  uint64_t seam_mismatches = 0;
  std::optional<DecimateStats> decimation;
  std::optional<VertexFitStats> vertex_fit;
  std::optional<FaceApertureStats> apertures;
  uint64_t smoothed_vertices = 0;  // vertices the thick-sheet smoothing moved
  std::optional<ErrorDensityStats> error_density;
  std::optional<MesherChoiceStats> mesher_choice;

  // The figures by name, the SCVD's and the topology nested, for the report.
  nlohmann::json Fields() const;
};

// The stats of `result`, its lengths made physical by `placement`.
SurfaceStats DescribeSurface(const SurfaceResult& result, const Placement& placement);

// Meshes `sheet` with one SCVD, or its mid-surface with options.method kMid (kAuto is the
// pipeline's: it builds both and keeps one; here it is the SCVD) (options.error_density is
// BuildRequestedSurface's, in error_density.h). `piece_of_voxel`, when not empty, labels each voxel
// with its object id (faces take their vertices' majority); otherwise faces carry their component
// id. Errors of BuildScvd pass through (kInvalidArgument for r <= 0 or r beyond the volume);
// kCancelled if asked.
absl::StatusOr<SurfaceResult> BuildSurface(const SheetAnalysis& sheet,
                                           const SurfaceOptions& options,
                                           std::span<const int32_t> piece_of_voxel = {},
                                           const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_SURFACE_BUILDER_H_
