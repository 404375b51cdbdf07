// RunPipeline: one job of the method from a volume to files — read the sheet phase,
// analyse it, optionally search r, build the surface mesh, score it, write meshes and a
// JSON report. Used by the offline CLI and by the worker runtime alike.
#ifndef SHEETMESH_WORKER_PIPELINE_RUN_PIPELINE_H_
#define SHEETMESH_WORKER_PIPELINE_RUN_PIPELINE_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/extract/extraction.h"
#include "worker/pipeline/extract/piece_geology.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/similarity/mesh_model.h"
#include "worker/pipeline/similarity/similarity.h"
#include "worker/pipeline/surface/radius_search.h"
#include "worker/pipeline/surface/surface_builder.h"
#include "worker/pipeline/tet/volume_mesher.h"
#include "worker/pipeline/voxel/sheet_input.h"
#include "worker/pipeline/voxel/thickness.h"

namespace sheetmesh {

struct ScoreOptions {
  PrismHeight height = PrismHeight::kFace;  // the mesh model of the headline similarity
  bool hausdorff = true;                    // also the symmetric Hausdorff distance
  std::vector<int> grid_rates = {2, 3, 4};  // grid-model baselines of Table 2 (empty: none)
};

struct OutputOptions {
  std::string dir;    // where files go (created); empty: write nothing
  bool ply = true;    // surface.ply
  bool vtp = true;    // surface.vtp
  bool obj = true;    // surface.obj
  bool model = true;  // with extraction: model.vdb (mask + labels) and
                      // model_labels_<dims>_u16.raw, and pieces.csv
  bool vtu = true;    // with a volume mesh: volume.vtu
  bool msh = true;    // volume.msh (Gmsh 4.1)
  bool inp = true;    // volume.inp (Abaqus)
};

struct PipelineOptions {
  SheetInput input;
  bool extract = false;  // run the feature extraction (Fig. 3) first
  ExtractionOptions extraction;
  SurfaceOptions surface;      // r = surface.scvd.radius_voxels unless searched
  bool search_radius = false;  // choose r with `radius_search`
  RadiusSearchOptions radius_search;
  ScoreOptions score;
  bool volume_mesh = false;  // tetrahedralize the box with the sheets inside
  VolumeMeshOptions volume;
  OutputOptions output;
};

// Stage names in the order RunPipeline reports them through Progress::Stage.
std::vector<std::string> PlannedStages(const PipelineOptions& options);

struct StageTime {
  std::string stage;
  double seconds = 0;
};

struct GridFigure {
  int rate = 0;
  double similarity = 0;
  uint64_t grid_quantity = 0;
};

struct PipelineReport {
  PipelineOptions options;  // as run (r as chosen)
  VolumeInfo volume;
  uint64_t sheet_voxels = 0;
  ThicknessStats thickness;
  uint32_t components = 0;
  // SCVD and mesh
  uint32_t generators = 0;
  int lloyd_iterations = 0;
  bool lloyd_converged = false;
  double energy = 0;
  uint64_t vertices = 0;
  uint64_t triangles = 0;
  double element_size_voxels = 0;  // mean edge length
  double area_voxels = 0;
  DualTriangleStats triangle_stats;
  TopologyReport topology;
  uint32_t skipped_components = 0;
  uint64_t skipped_voxels = 0;
  // extraction (when run)
  std::vector<ExtractionStep> extraction_steps;
  uint64_t min_object_voxels = 0;  // M as used
  uint64_t model_voxels = 0;       // voxels of the extracted model
  uint32_t pieces = 0;
  std::vector<PieceGeology> geology;
  // similarity
  SimilarityScore similarity;      // against the meshed set (the extracted model, or the
                                   // input's sheet phase), model of `score.height`
  SimilarityScore similarity_raw;  // against the input's sheet phase (with extraction)
  double shell_similarity = 0;     // the other prism model (per-vertex if height is face)
  std::vector<GridFigure> grid;
  RadiusChoice radius_choice;  // when r was searched
  // volume mesh (when made)
  bool has_volume_mesh = false;
  uint64_t volume_nodes = 0;
  uint64_t volume_tets = 0;
  uint64_t volume_sheet_faces = 0;
  TetQuality volume_quality;
  Conformity volume_conformity;
  uint32_t volume_snapped = 0;
  uint32_t volume_snap_held = 0;
  uint32_t volume_repaired = 0;
  uint32_t volume_flipped = 0;
  uint32_t volume_dropped_caps = 0;
  uint32_t volume_dropped_overlaps = 0;
  uint32_t volume_closed_slits = 0;
  uint32_t volume_opened_wedges = 0;
  uint32_t volume_box_points = 0;
  uint32_t volume_seed_points = 0;
  TetImproveReport volume_improvement;
  uint32_t volume_rederived_facets = 0;
  double voxels_per_tet = 0;  // the paper's 1 : 6704 is 6704 here
  std::vector<StageTime> timings;
  std::vector<std::string> files;  // written, relative to output.dir

  // The report as JSON (the report.json artifact).
  std::string ToJson() const;
};

// Runs the job. Every stage reports through `progress.Stage(name)`. Errors of any stage
// pass through with their codes; kCancelled if asked. Files appear atomically; a failed
// run leaves no half-written file.
absl::StatusOr<PipelineReport> RunPipeline(const PipelineOptions& options,
                                           const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_RUN_PIPELINE_H_
