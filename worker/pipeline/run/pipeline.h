// RunPipeline: one job of the method from a volume to files — read the sheet phase,
// analyse it, optionally search r, build the surface mesh, score it, write meshes and a
// JSON report. Used by the offline CLI and by the worker runtime alike.
#ifndef SHEETMESH_WORKER_PIPELINE_RUN_PIPELINE_H_
#define SHEETMESH_WORKER_PIPELINE_RUN_PIPELINE_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/extract/extraction.h"
#include "worker/pipeline/extract/piece_geology.h"
#include "worker/pipeline/flow/image_permeability.h"
#include "worker/pipeline/flow/permeability.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/run/pipeline_options.h"
#include "worker/pipeline/similarity/mesh_model.h"
#include "worker/pipeline/similarity/similarity.h"
#include "worker/pipeline/surface/grey_apertures.h"
#include "worker/pipeline/surface/radius_search.h"
#include "worker/pipeline/surface/representation.h"
#include "worker/pipeline/surface/surface_builder.h"
#include "worker/pipeline/tet/split_mesh.h"
#include "worker/pipeline/tet/volume_mesher.h"
#include "worker/pipeline/voxel/sheet_input.h"
#include "worker/pipeline/voxel/thickness.h"

namespace sheetmesh {

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

// How faithful the mesh is (formula 5), against the set it meshed and, with extraction,
// against the input's raw phase; the other prism model and the grid baselines of Table 2.
struct SimilarityReport {
  bool against_model = false;          // the meshed set is the extracted model
  SimilarityScore score;               // of `score.height`'s prisms
  std::optional<SimilarityScore> raw;  // against the input's phase (with extraction)
  double shell_similarity = 0;         // the other prism model
  std::vector<GridFigure> grid;

  // Where the mesh scores under every grid model of `grid` (the paper's Table 2 baselines,
  // each with far more cells than the mesh has triangles: a floor any mesh should beat),
  // the line that says so and what to do (the report's similarity.floor_warning, printed
  // by the CLIs, issued by the Python client, shown on the job page); none otherwise.
  std::optional<std::string> FloorWarning() const;

  nlohmann::json Fields() const;
};

// Everything a run says of itself: what it read, what each stage made, the options as
// run, the time of each stage and the files written. Each stage's result lists its own
// fields; ToJson nests them, for the CLI and the service alike.
struct PipelineReport {
  PipelineOptions options;  // as run (r as chosen)
  VolumeInfo volume;
  PhaseSelection selection;         // the sheet phase as selected (a threshold's window)
  std::optional<double> threshold;  // with input.threshold: the value used (Otsu's)
  uint64_t sheet_voxels = 0;
  ThicknessStats thickness;  // of the meshed set
  uint32_t components = 0;
  std::optional<ExtractionSummary> extraction;
  std::vector<PieceGeology> geology;          // with extraction
  std::optional<RadiusChoice> radius_choice;  // when r was searched
  std::optional<SurfaceStats> surface;
  std::optional<RepresentationReport> representation;  // unless every piece is a sheet
  std::optional<SimilarityReport> similarity;
  std::optional<VolumeMeshStats> volume_mesh;
  std::optional<SplitStats> volume_split;       // with output.split: what the split did
  std::optional<PermeabilityResult> flow;       // with flow: the permeability tensor
  std::optional<ImagePermeability> flow_image;  // and the image's, where the volume is small
  std::string flow_image_skipped;               // why not, where it is not
  // With input.grey: what the sheets were found on, and the apertures from the grey levels.
  std::optional<SheetnessStats> sheetness;
  std::optional<GreyApertureStats> grey_apertures;
  std::vector<StageTime> timings;
  std::vector<std::string> files;  // written, relative to output.dir
  // Outputs left out because they are dense (the size of the box) and were not asked for:
  // (name, why).
  std::vector<std::pair<std::string, std::string>> not_written;
  std::vector<std::string> previews;  // each preview's description, as JSON text
  // A later stage that failed after the surface was made and scored (the volume mesh): its
  // name and error; what was done before it is written all the same.
  std::string failed_stage;
  std::string error;

  // The report as JSON (the report.json artifact): the sections this report has.
  std::string ToJson() const;
};

// Runs the job. Every stage reports through `progress.Stage(name)`. Errors of any stage
// pass through with their codes; kCancelled if asked. Files appear atomically; a failed
// run leaves no half-written file. When the volume stage fails (for another reason than a
// cancel or the time limit) and output.dir is set, the surface, its score, previews and a
// report naming the failed stage are written first, and the error says so and lists them
// (KeptFiles).
absl::StatusOr<PipelineReport> RunPipeline(const PipelineOptions& options,
                                           const Progress& progress = {});

// The same on a sheet phase read before (the merge of bricks, brick/brick_merge.h): the
// "read" stage takes it as it is; options.input names the volume it came from.
// kInvalidArgument with input.grey, which needs the grey levels.
absl::StatusOr<PipelineReport> RunPipelineOnPhase(const PipelineOptions& options, SheetPhase phase,
                                                  const Progress& progress = {});

// The files a failed run kept in output.dir (their names, in the order written): empty
// unless the status is the error of a run that kept some. WithKeptFiles attaches them.
std::vector<std::string> KeptFiles(const absl::Status& status);
absl::Status WithKeptFiles(absl::Status status, const std::vector<std::string>& files);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_RUN_PIPELINE_H_
