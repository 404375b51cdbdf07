#include "worker/pipeline/run/pipeline.h"

#include <sys/resource.h>

#include <filesystem>
#include <mutex>
#include <new>
#include <optional>

#include "absl/strings/cord.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "common/file_util.h"
#include "common/status_macros.h"
#include "worker/pipeline/extract/separation.h"
#include "worker/pipeline/mesh/mesh_io.h"
#include "worker/pipeline/preview/previews.h"
#include "worker/pipeline/run/parameters.h"
#include "worker/pipeline/run/pipeline_outputs.h"
#include "worker/pipeline/surface/error_density.h"
#include "worker/pipeline/surface/mesher_choice.h"
#include "worker/pipeline/surface/mid_surface.h"
#include "worker/pipeline/tet/volume_mesh_io.h"
#include "worker/pipeline/volume/vdb_io.h"
#include "worker/pipeline/voxel/label_volume.h"
#include "worker/pipeline/voxel/voxel_set_vdb.h"

namespace sheetmesh {
namespace {

// Times a stage and appends it to the report.
class StageTimer {
 public:
  StageTimer(PipelineReport* report, std::string stage)
      : report_(report), stage_(std::move(stage)), start_(absl::Now()) {}
  ~StageTimer() {
    report_->timings.push_back({stage_, absl::ToDoubleSeconds(absl::Now() - start_)});
  }

 private:
  PipelineReport* report_;
  std::string stage_;
  absl::Time start_;
};

// Formula 5 for the mesh's prisms and bodies against the meshed set (and the raw phase, with
// extraction), the other prism model and the grid baselines.
absl::StatusOr<SimilarityReport> Score(const TriangleMesh& mesh, const SheetAnalysis& sheet,
                                       const SheetPhase& phase, const PipelineOptions& options,
                                       const Progress& p) {
  const PrismHeight other =
      options.score.height == PrismHeight::kFace ? PrismHeight::kVertex : PrismHeight::kFace;
  SimilarityReport sim;
  sim.against_model = options.extract;
  SM_ASSIGN_OR_RETURN(VoxelSet prisms, VoxelizeMesh(mesh, sheet.set.dims(), options.score.height));
  sim.score = ScoreModel(prisms, sheet.set);
  if (options.score.hausdorff) {
    SM_ASSIGN_OR_RETURN(sim.score.hausdorff, HausdorffDistance(prisms, sheet.set, p.Sub(0.2, 0.6)));
  }
  SM_ASSIGN_OR_RETURN(VoxelSet shell, VoxelizeMesh(mesh, sheet.set.dims(), other));
  sim.shell_similarity = ScoreModel(shell, sheet.set).similarity;
  if (options.extract) sim.raw = ScoreModel(prisms, phase.sheet);
  for (int k : options.score.grid_rates) {
    sim.grid.push_back({k, ScoreModel(GridModel(sheet.set, k), sheet.set).similarity,
                        GridQuantity(sheet.set.dims(), k)});
  }
  SM_RETURN_IF_ERROR(p.Update(1.0));
  return sim;
}

// The permeability in darcy per axis (the tensor's diagonal, the permeameter, the image's
// reference where it ran) and the principal values, for the previews.
LogBarChart PermeabilityChart(const PipelineReport& report) {
  const PermeabilityResult& k = *report.flow;
  LogBarChart c;
  c.file = "preview_permeability.png";
  c.kind = "permeability";
  c.title = "permeability in darcy, log scale";
  c.series = {"the tensor (pressure linear on the box)", "permeameter (sides closed)"};
  if (report.flow_image) c.series.push_back("the image: permeameter on the voxel grid");
  static const char* kAxis[3] = {"x", "y", "z"};
  for (int d = 0; d < 3; ++d) {
    std::vector<double> v = {k.tensor[d][d] / kSquareMetresPerDarcy,
                             k.permeameter[d] / kSquareMetresPerDarcy};
    if (report.flow_image) v.push_back(report.flow_image->tensor[d][d] / kSquareMetresPerDarcy);
    c.groups.emplace_back(kAxis[d], v);
  }
  for (int i = 0; i < 3; ++i) {
    c.groups.emplace_back(absl::StrCat("k", i + 1),
                          std::vector<double>{k.principal[i] / kSquareMetresPerDarcy});
  }
  // (The previews' font has no apostrophe.)
  c.caption = {"x, y, z: along each axis; k1-k3: principal values of the tensor",
               "1 darcy = 9.87e-13 square metres"};
  if (report.flow_image) {
    c.caption.push_back(absl::StrFormat(
        "mesh / image per axis: %.3f, %.3f, %.3f", report.flow_image->mesh_to_image[0],
        report.flow_image->mesh_to_image[1], report.flow_image->mesh_to_image[2]));
  }
  return c;
}

// The previews of `phase` (the input's sheet phase) and `mesh`, described in the report.
absl::Status WritePreviews(const std::string& dir, const VoxelSet& phase, const TriangleMesh& mesh,
                           const Placement& placement, PipelineReport* report) {
  for (int k = 0; k < 4; ++k) {
    const absl::Time start = absl::Now();
    Preview p = k < 3 ? SlicePreview(phase, mesh, k, placement) : ThicknessPreview(mesh, placement);
    SM_ASSIGN_OR_RETURN(std::string png, EncodePng(p.image));
    p.fields["seconds"] = absl::ToDoubleSeconds(absl::Now() - start);  // drawn and encoded
    SM_RETURN_IF_ERROR(WriteFileAtomically((std::filesystem::path(dir) / p.file).string(), png));
    report->files.push_back(p.file);
    p.fields["file"] = p.file;
    p.fields["width"] = p.image.width;
    p.fields["height"] = p.image.height;
    report->previews.push_back(p.fields.dump());
  }
  if (report->flow) {
    const Preview p = LogBarPreview(PermeabilityChart(*report));
    SM_ASSIGN_OR_RETURN(std::string png, EncodePng(p.image));
    SM_RETURN_IF_ERROR(WriteFileAtomically((std::filesystem::path(dir) / p.file).string(), png));
    report->files.push_back(p.file);
    nlohmann::json fields = p.fields;
    fields["file"] = p.file;
    fields["width"] = p.image.width;
    fields["height"] = p.image.height;
    report->previews.push_back(fields.dump());
  }
  return absl::OkStatus();
}

// The files of options.output into options.output.dir, listed in report->files, the report
// last. `volume` is null without a volume mesh.
absl::Status WriteOutputs(const PipelineOptions& options, const Placement& pl,
                          const VoxelSet& phase, const TriangleMesh& mesh,
                          const LabelledVoxels& model, const LabelledVoxels& dropped,
                          const TetMesh* volume, const VolumeFields* fields,
                          PipelineReport* report) {
  const std::string& dir = options.output.dir;
  SM_RETURN_IF_ERROR(MakeDirs(dir));
  auto path = [&](const std::string& name) { return (std::filesystem::path(dir) / name).string(); };
  SM_RETURN_IF_ERROR(WriteSurfaceFiles(dir, mesh, pl, options.output, &report->files));
  if (options.extract && options.output.model) {
    SM_RETURN_IF_ERROR(WriteVoxelSetVdb(path("model.vdb"), model.set, model.label, pl, "model"));
    report->files.push_back("model.vdb");
    SM_RETURN_IF_ERROR(WriteFileAtomically(path("pieces.csv"), PieceGeologyCsv(report->geology)));
    report->files.push_back("pieces.csv");
  }
  // Dense label volumes, the size of the box: only when asked, compressed unless raw is.
  const bool raw = options.output.label_volume == DenseLabels::kRaw;
  const auto dense = [&](const char* stem, const LabelledVoxels& labels) -> absl::Status {
    const std::string name =
        absl::StrCat(stem, "_", model.set.dims().ToString(), raw ? "_u16.raw" : ".h5");
    SM_RETURN_IF_ERROR(
        WriteLabelVolume(labels, path(name), raw ? VolumeFormat::kRaw : VolumeFormat::kHdf5, pl));
    report->files.push_back(name);
    return absl::OkStatus();
  };
  if (options.extract && options.output.model) {
    if (options.output.label_volume != DenseLabels::kNone) {
      SM_RETURN_IF_ERROR(dense("model_labels", model));
    } else {
      report->not_written.emplace_back(
          "model_labels",
          absl::StrCat("a dense label volume of ", model.set.dims().num_voxels(),
                       " voxels; model.vdb has the labels sparse (output.label_volume=hdf5 or "
                       "raw writes it)"));
    }
  }
  // Labels 1 refine, 2 specks, 3 crossings, 4 minor pieces; 0 kept or never sheet.
  if (options.extract && options.output.dropped)
    SM_RETURN_IF_ERROR(dense("dropped_labels", dropped));
  if (volume != nullptr) {
    SplitStats split;
    SM_RETURN_IF_ERROR(
        WriteVolumeFiles(dir, *volume, options.output, &report->files, fields, &split));
    if (options.output.split) report->volume_split = split;
  }
  if (options.output.previews) SM_RETURN_IF_ERROR(WritePreviews(dir, phase, mesh, pl, report));
  report->files.push_back("report.json");
  return WriteFileAtomically(path("report.json"), report->ToJson());
}

}  // namespace

std::vector<std::string> PlannedStages(const PipelineOptions& options) {
  std::vector<std::string> stages = {"read"};
  if (options.extract) {
    const ExtractionOptions& e = options.extraction;
    if (e.refine) stages.push_back("refine");
    if (e.detect) stages.push_back("detect");
    if (e.separate) stages.push_back("separate");
    if (e.remove_minor) stages.push_back("remove_minor");
    if (e.recover) stages.push_back("recover");
  }
  stages.push_back("analyze");
  if (SeparatesWithoutExtraction(options)) {
    stages.push_back("separate");
    if (options.extraction.remove_minor) stages.push_back("remove_minor");
    if (options.extraction.recover) stages.push_back("recover");
  }
  // The search builds the surface it chooses.
  stages.push_back(options.search_radius ? "search-r" : "surface");
  if (options.representation.mode != RepresentationMode::kSheet) stages.push_back("representation");
  stages.push_back("similarity");
  if (MeshesVolume(options)) stages.push_back("volume");
  if (options.flow.enabled) stages.push_back("flow");
  if (!options.output.dir.empty()) stages.push_back("write");
  return stages;
}

namespace {

absl::StatusOr<PipelineReport> RunStages(const PipelineOptions& options, const Progress& progress,
                                         std::optional<SheetPhase> given);

}  // namespace

constexpr char kKeptFiles[] = "sheetmesh.dev/kept-files";

std::vector<std::string> KeptFiles(const absl::Status& status) {
  const auto kept = status.GetPayload(kKeptFiles);
  if (!kept) return {};
  return absl::StrSplit(std::string(*kept), '\n', absl::SkipEmpty());
}

absl::Status WithKeptFiles(absl::Status status, const std::vector<std::string>& files) {
  if (!status.ok() && !files.empty()) {
    status.SetPayload(kKeptFiles, absl::Cord(absl::StrJoin(files, "\n")));
  }
  return status;
}

namespace {

// Remembers the stage last reported, for an error that cannot say where it happened.
class LastStage : public ProgressObserver {
 public:
  explicit LastStage(ProgressObserver* inner) : inner_(inner) {}
  bool OnProgress(absl::string_view stage, double fraction, absl::string_view message) override {
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (stage_ != stage) stage_ = std::string(stage);
    }
    return inner_ == nullptr || inner_->OnProgress(stage, fraction, message);
  }
  std::string stage() {
    std::lock_guard<std::mutex> lock(mu_);
    return stage_.empty() ? std::string("read") : stage_;
  }

 private:
  ProgressObserver* inner_;
  std::mutex mu_;
  std::string stage_;
};

// What this process may allocate, for the message of a run that ran out: "at most 17.6 GiB of
// address space" or "".
std::string AddressSpaceLimit() {
  struct rlimit rl;
  if (::getrlimit(RLIMIT_AS, &rl) != 0 || rl.rlim_cur == RLIM_INFINITY) return "";
  return absl::StrFormat(" (this process may use %.2f GiB of address space)",
                         static_cast<double>(rl.rlim_cur) / double(uint64_t{1} << 30));
}

absl::StatusOr<PipelineReport> RunWithDeadline(const PipelineOptions& options,
                                               const Progress& progress,
                                               std::optional<SheetPhase> given);

// A stage that asks for more memory than there is ends the run with an error naming it, not
// the process: the outputs are written only at the end, atomically, so nothing is half made.
absl::StatusOr<PipelineReport> RunWithin(const PipelineOptions& options, const Progress& progress,
                                         std::optional<SheetPhase> given) {
  LastStage last(progress.observer());
  try {
    return RunWithDeadline(options, Progress(&last, progress.stage()), std::move(given));
  } catch (const std::bad_alloc&) {
    return absl::ResourceExhaustedError(absl::StrCat(
        options.input.path, ": out of memory in stage ", last.stage(), AddressSpaceLimit(),
        "; give the job more memory (sheetmesh-pipeline --memory_limit_gb, the worker's "
        "--job_memory_gb), or less to hold: a larger r, or a region of the volume "
        "(input.region)"));
  }
}

absl::StatusOr<PipelineReport> RunWithDeadline(const PipelineOptions& options,
                                               const Progress& progress,
                                               std::optional<SheetPhase> given) {
  if (options.time_limit_seconds <= 0) return RunStages(options, progress, std::move(given));
  DeadlineObserver deadline(progress.observer(),
                            absl::Now() + absl::Seconds(options.time_limit_seconds));
  absl::StatusOr<PipelineReport> report =
      RunStages(options, Progress(&deadline, progress.stage()), std::move(given));
  if (!report.ok() && report.status().code() == absl::StatusCode::kCancelled) {
    if (std::optional<std::string> stage = deadline.expired_in()) {
      return absl::DeadlineExceededError(absl::StrCat("the run went past its time limit of ",
                                                      options.time_limit_seconds,
                                                      " s (time_limit_seconds) in stage ", *stage));
    }
  }
  return report;
}

}  // namespace

absl::StatusOr<PipelineReport> RunPipeline(const PipelineOptions& options,
                                           const Progress& progress) {
  return RunWithin(options, progress, std::nullopt);
}

absl::StatusOr<PipelineReport> RunPipelineOnPhase(const PipelineOptions& options, SheetPhase phase,
                                                  const Progress& progress) {
  if (options.grey.enabled) {
    return absl::InvalidArgumentError(
        "input.grey finds the sheets in the grey levels, which a sheet phase read before (by "
        "bricks) does not carry: run it on the volume in one process");
  }
  return RunWithin(options, progress, std::move(phase));
}

namespace {

absl::StatusOr<PipelineReport> RunStages(const PipelineOptions& options, const Progress& progress,
                                         std::optional<SheetPhase> given) {
  SM_RETURN_IF_ERROR(CheckParameters(options));
  PipelineReport report;
  report.options = options;
  SheetPhase phase;
  std::optional<GreySheetPhase> grey;
  {
    StageTimer t(&report, "read");
    if (given) {
      phase = *std::move(given);
      given.reset();
      SM_RETURN_IF_ERROR(progress.Stage("read").Update(1.0));
    } else if (options.grey.enabled) {
      SM_ASSIGN_OR_RETURN(grey, LoadGreySheetPhase(options.input, options.grey.levels,
                                                   options.grey.sheetness, progress.Stage("read")));
      phase = grey->phase;
      report.sheetness = grey->sheetness;
    } else {
      SM_ASSIGN_OR_RETURN(phase, LoadSheetPhase(options.input, progress.Stage("read")));
    }
  }
  if (options.flow.enabled && MetresPerUnit(phase.info.placement.unit) == 0) {
    // Before any work: a permeability needs lengths in metres.
    return absl::InvalidArgumentError(
        absl::StrCat(options.input.path,
                     ": flow gives a permeability in m² and needs the volume's length "
                     "unit, which is ",
                     phase.info.placement.unit.empty() ? std::string("not known")
                                                       : "\"" + phase.info.placement.unit + "\"",
                     ": give input.unit (", kKnownLengthUnits,
                     ") and input.spacing, e.g. --unit=um "
                     "--spacing=5,5,5"));
  }
  report.volume = phase.info;
  report.selection = phase.selection;
  report.threshold = phase.threshold;
  report.sheet_voxels = phase.sheet.size();
  // The set that is meshed: the extracted model, or the input's sheet phase as it is.
  VoxelSet meshed = phase.sheet;
  std::vector<int32_t> piece_of_voxel;
  LabelledVoxels model, dropped;
  if (options.extract) {
    StageTimer t(&report, "extract");
    // The extension's claims share the job's memory budget with the readers'.
    ExtractionOptions extraction = options.extraction;
    const int64_t budget = MemoryBudget(options.input.open.limits);
    extraction.detect_extend.memory_bytes = budget;
    extraction.recover_extend.memory_bytes = budget;
    SM_ASSIGN_OR_RETURN(ExtractionResult ex, ExtractFeatures(phase.sheet, extraction, progress));
    model = std::move(ex.model);
    dropped = std::move(ex.dropped);
    report.extraction = std::move(static_cast<ExtractionSummary&>(ex));
    meshed = model.set;
    piece_of_voxel = model.label;
  }
  SheetAnalysis sheet;
  {
    StageTimer t(&report, "analyze");
    SM_ASSIGN_OR_RETURN(sheet, AnalyzeSheet(std::move(meshed), progress.Stage("analyze")));
  }
  report.thickness = sheet.thickness_stats;
  report.thickness.histogram.clear();
  report.components = sheet.components.count();
  // With surface.mesher auto, the SCVD's pieces where the mid-surface's are cut anew.
  std::vector<int32_t> scvd_pieces;
  if (SeparatesWithoutExtraction(options)) {
    scvd_pieces = piece_of_voxel;
    // A mid-surface is a height field per piece: a component whose layers are not (a steep
    // crossing) is cut as separation (Algorithm 2) cuts it, the junctions cut away.
    StageTimer t(&report, "separate");
    const std::vector<uint32_t> components = sheet.components.VoxelLabels(sheet.set);
    const std::vector<int32_t> whole(components.begin(), components.end());
    SM_ASSIGN_OR_RETURN(
        piece_of_voxel,
        MidSurfacePieces(sheet.set, whole, [&]() -> absl::StatusOr<std::vector<int32_t>> {
          // Separation with its own tidying: pieces below M to the junction, the gaps it cut
          // regrown within the phase (extraction without detection's additions).
          ExtractionOptions e = options.extraction;
          e.refine = false;
          e.detect = false;
          e.separate = true;
          e.recover_extend.memory_bytes = MemoryBudget(options.input.open.limits);
          SM_ASSIGN_OR_RETURN(const ExtractionResult parts,
                              ExtractFeatures(sheet.set, e, progress.Stage("separate")));
          std::vector<int32_t> separated(sheet.set.size(), -1);
          parts.model.set.ForEachVoxel([&](uint64_t i, int32_t x, int32_t y, int32_t z) {
            const int64_t at = sheet.set.Find(x, y, z);
            if (at >= 0) separated[at] = parts.model.label[i];
          });
          return separated;
        }));
  }

  SurfaceOptions surface = options.surface;
  if (surface.fit_vertices == VertexFit::kAuto) {
    // Measured over the volume mesh sweep: moved vertices leave the volume mesh more slivers
    // (bench/RESULTS.md, issue 42); where a volume mesh follows, its angles come first.
    surface.fit_vertices = MeshesVolume(options) ? VertexFit::kNone : VertexFit::kRim;
  }
  // The surface of one mesher (the search hands back the surface it chose).
  auto build = [&](const SurfaceOptions& o, std::span<const int32_t> pieces,
                   const Progress& p) -> absl::StatusOr<RadiusSearchResult> {
    if (options.search_radius) return SearchRadius(sheet, o, options.radius_search, pieces, p);
    RadiusSearchResult built;
    SM_ASSIGN_OR_RETURN(built.surface, BuildRequestedSurface(sheet, o, pieces, p));
    return built;
  };
  SurfaceResult result;
  {
    StageTimer t(&report, options.search_radius ? "search-r" : "surface");
    const Progress p = progress.Stage(options.search_radius ? "search-r" : "surface");
    RadiusSearchResult found;
    if (surface.method != SurfaceMethod::kAuto) {
      SM_ASSIGN_OR_RETURN(found, build(surface, piece_of_voxel, p));
    } else {
      // Both meshers, each with its own pieces (without extraction the mid-surface's were
      // cut anew); the one kept carries on with its pieces.
      SM_ASSIGN_OR_RETURN(found, BuildWithBothMeshers(
                                     sheet, options.score.height,
                                     [&](SurfaceMethod method, const Progress& q) {
                                       SurfaceOptions o = surface;
                                       o.method = method;
                                       const bool own =
                                           method == SurfaceMethod::kMid || options.extract;
                                       return build(o, own ? piece_of_voxel : scvd_pieces, q);
                                     },
                                     p));
      if (!found.surface.mesher_choice->kept_mid && !options.extract) {
        piece_of_voxel = std::move(scvd_pieces);
      }
    }
    if (options.search_radius) {
      surface.scvd.radius_voxels = found.choice.radius;
      surface.triangles = found.choice.decimated_to;
      report.options.surface.scvd.radius_voxels = found.choice.radius;
      report.radius_choice = std::move(found.choice);
    }
    result = std::move(found.surface);
  }
  if (result.mesh.num_faces() == 0) {
    // An empty mesh scores 0 and would give a volume mesh of the box alone: not a result.
    return absl::InvalidArgumentError(
        absl::StrCat("r = ", surface.scvd.radius_voxels, " voxels gave no triangle: each of the ",
                     sheet.components.count(), " components of the sheet phase (the largest ",
                     sheet.components.sizes.empty() ? 0 : sheet.components.sizes[0],
                     " voxels) is too small for three cells of that size; lower r (--r)"));
  }
  if (options.representation.mode != RepresentationMode::kSheet) {
    StageTimer t(&report, "representation");
    RepresentationOptions representation = options.representation;
    // Thin pieces as bodies only where asked (surface.thin_bodies) and the surface is the
    // result: a volume mesh would fill them with flat tetrahedra, and grey apertures are
    // measured across sheets.
    representation.try_thin_bodies =
        options.representation.try_thin_bodies && !MeshesVolume(options) && !grey;
    SM_ASSIGN_OR_RETURN(report.representation,
                        ChooseRepresentation(sheet, piece_of_voxel, representation, &result.mesh,
                                             progress.Stage("representation")));
  }
  if (grey) {
    // The apertures from the attenuation the sheets miss; the prisms' heights, which the
    // similarity scores against the sheets found, stay.
    GreyApertureOptions ao;
    ao.psf_sigma_voxels = options.grey.psf_sigma_voxels;
    SM_ASSIGN_OR_RETURN(report.grey_apertures,
                        SetGreyApertures(&result.mesh, grey->grey, grey->levels, ao));
  }
  const TriangleMesh& mesh = result.mesh;
  if (surface.triangles > 0 && mesh.num_faces() > (1 + kTriangleTolerance) * surface.triangles) {
    return absl::InvalidArgumentError(absl::StrCat("triangles = ", surface.triangles,
                                                   " is below the fewest this sheet can be meshed "
                                                   "with: ",
                                                   mesh.num_faces(),
                                                   " (its outline and junctions need them)"));
  }
  report.surface = DescribeSurface(result, phase.info.placement);

  {
    StageTimer t(&report, "similarity");
    SM_ASSIGN_OR_RETURN(report.similarity,
                        Score(mesh, sheet, phase, options, progress.Stage("similarity")));
    if (options.extract) {
      report.geology = ComputePieceGeology(LabelledVoxels{sheet.set, piece_of_voxel},
                                           sheet.thickness, mesh, phase.info.placement);
      if (report.grey_apertures && report.grey_apertures->measured) {
        // Each piece's aperture is its faces' from the grey levels, not its voxels' count.
        UseFaceApertures(mesh, phase.info.placement, &report.geology);
      }
    }
  }

  VolumeMeshResult volume;
  VolumeFields flow_fields;  // with flow: the pressures and velocities, for volume.vtu
  absl::Status volume_failed;
  if (MeshesVolume(options)) {
    // The volume stage's time ends where the flow's begins: the timings do not overlap.
    std::optional<StageTimer> volume_timer;
    volume_timer.emplace(&report, "volume");
    VolumeMeshOptions vo = options.volume;
    // A PLC TetGen fails on is kept beside the outputs: the input of a bug report.
    if (!options.output.dir.empty() && MakeDirs(options.output.dir).ok()) {
      vo.tetgen.failed_plc_path = options.output.dir + "/tetgen_failed.poly";
    }
    absl::StatusOr<VolumeMeshResult> built =
        BuildVolumeMesh(mesh, phase.info.dims, phase.info.placement, vo, progress.Stage("volume"));
    if (built.ok()) {
      volume = *std::move(built);
      // The sheets the user gets in the volume mesh, scored as the surface was.
      SM_ASSIGN_OR_RETURN(
          VoxelSet delivered,
          VoxelizeMesh(volume.mesh.SheetSurface(phase.info.placement), sheet.set.dims(),
                       PrismHeight::kFace));  // the volume mesh carries a thickness per face
      volume.delivered_similarity = ScoreModel(delivered, sheet.set).similarity;
      report.volume_mesh = static_cast<const VolumeMeshStats&>(volume);
      if (options.flow.enabled) {
        volume_timer.reset();
        StageTimer flow_timer(&report, "flow");
        const Progress flow = progress.Stage("flow");
        SM_ASSIGN_OR_RETURN(report.flow, SolvePermeability(volume.mesh, options.flow,
                                                           flow.Sub(0, 0.5), &flow_fields));
        // The image's own answer beside it: the cubic law on the sheet voxels' thickness.
        if (!options.flow.image_reference) {
          report.flow_image_skipped = "not asked (permeability.image_reference false)";
        } else {
          const double m = report.flow->metres_per_unit;
          const Vec3& s = phase.info.placement.spacing;
          absl::StatusOr<ImagePermeability> image =
              SolveImagePermeability(sheet.set, sheet.thickness, Vec3(s.x * m, s.y * m, s.z * m),
                                     options.flow, kImageReferenceCells, flow.Sub(0.5, 1));
          if (image.ok()) {
            CompareToImage(*report.flow, &*image);
            report.flow_image = *std::move(image);
          } else if (image.status().code() == absl::StatusCode::kResourceExhausted) {
            report.flow_image_skipped = std::string(image.status().message());
          } else {
            return image.status();
          }
        }
      }
    } else {
      // Cancelled or out of time: stop. Otherwise the surface and its score stand.
      const absl::StatusCode code = built.status().code();
      if (options.output.dir.empty() || code == absl::StatusCode::kCancelled ||
          code == absl::StatusCode::kDeadlineExceeded) {
        return built.status();
      }
      volume_failed = built.status();
      report.failed_stage = "volume";
      report.error = std::string(built.status().message());
    }
  }

  if (!options.output.dir.empty()) {
    StageTimer t(&report, "write");
    SM_RETURN_IF_ERROR(WriteOutputs(options, phase.info.placement, phase.sheet, mesh, model,
                                    dropped, report.volume_mesh ? &volume.mesh : nullptr,
                                    report.flow ? &flow_fields : nullptr, &report));
    SM_RETURN_IF_ERROR(progress.Stage("write").Update(1.0));
  }
  if (!volume_failed.ok()) {
    return WithKeptFiles(
        absl::Status(
            volume_failed.code(),
            absl::StrCat(volume_failed.message(), " (the volume stage failed; kept in ",
                         options.output.dir, ": ", absl::StrJoin(report.files, ", "), ")")),
        report.files);
  }
  return report;
}

}  // namespace

}  // namespace sheetmesh
