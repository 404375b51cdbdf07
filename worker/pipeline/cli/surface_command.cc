#include "worker/pipeline/cli/surface_command.h"

#include <unistd.h>

#include <algorithm>
#include <iostream>
#include <mutex>
#include <nlohmann/json.hpp>

#include "absl/strings/match.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "common/file_util.h"
#include "common/json_text.h"
#include "common/progress_line.h"
#include "common/status_macros.h"
#include "worker/pipeline/brick/bricks.h"
#include "worker/pipeline/flow/permeability.h"
#include "worker/pipeline/mesh/mesh_io.h"
#include "worker/pipeline/run/parameters.h"
#include "worker/pipeline/run/pipeline_outputs.h"
#include "worker/pipeline/similarity/mesh_model.h"
#include "worker/pipeline/similarity/similarity.h"
#include "worker/pipeline/tet/volume_mesh_io.h"

namespace sheetmesh {
namespace {

// The split along the sheets, where asked.
void PrintSplit(const std::optional<SplitStats>& s, std::ostream& out) {
  if (!s) return;
  out << absl::StrFormat(
      "split       %d sheet nodes, %d copies added (%d kept single on a rim); %d interfaces, %d "
      "closed at a rim\n",
      s->sheet_nodes, s->added_nodes, s->rim_nodes, s->interfaces, s->closed_faces);
}

void PrintVolumeMesh(const VolumeMeshStats& v, std::ostream& out) {
  const TetQuality& q = v.quality;
  out << absl::StrFormat(
      "volume mesh %d nodes, %d tetrahedra (1 : %.0f of the voxels), %d sheet faces; %d of %d "
      "sheet triangles conform\n",
      v.nodes, v.tetrahedra, v.voxels_per_tet, v.sheet_faces, v.conformity.conforming,
      v.conformity.sheet_triangles);
  out << absl::StrFormat(
      "  quality   min dihedral min %.2f° mean %.2f°; gamma %.2f/%.2f; edge aspect %.2f/%.2f; "
      "radius aspect %.2f/%.2f (min/mean)\n",
      q.min_dihedral.min, q.min_dihedral.mean, q.gamma.min, q.gamma.mean, q.edge_aspect.min,
      q.edge_aspect.mean, q.radius_aspect.min, q.radius_aspect.mean);
  if (v.angle_warning) out << "  warning   " << v.angle_warning->Line() << "\n";
  if (v.improvement.time_limited) {
    out << absl::StrFormat(
        "  warning   the improvement stopped at tet.time_limit_seconds after %.1f s, its mesh "
        "kept as it was (raise the limit for better angles)\n",
        v.improvement.seconds);
  } else if (absl::StartsWith(v.sliver_refinement.stopped, "tet.time_limit_seconds")) {
    out << "  warning   the sliver rounds stopped at tet.time_limit_seconds\n";
  }
  if (v.second_try.tried) {
    out << absl::StrFormat("  2nd try   from moved lattice seeds: min %.2f° then %s; %s kept\n",
                           v.second_try.min_dihedral_first,
                           v.second_try.stopped.empty()
                               ? absl::StrFormat("%.2f°", v.second_try.min_dihedral_second)
                               : absl::StrCat("not finished (", v.second_try.stopped, ")"),
                           v.second_try.kept ? "the second" : "the first");
  } else if (!v.second_try.stopped.empty()) {
    out << "  2nd try   not made: " << v.second_try.stopped << "\n";
  }
  if (v.delivered_similarity) {
    out << absl::StrFormat("  sheets    as the volume mesh has them: similarity %.4f\n",
                           *v.delivered_similarity);
  }
  for (const VolumeMeshStats::BodyRegion& b : v.bodies) {
    out << absl::StrFormat("  body %d   %d tetrahedra, volume %.6g\n", b.piece, b.tetrahedra,
                           b.volume);
  }
}

// The run's progress on stderr (stdout keeps the results): a bar on a terminal, lines
// otherwise, each stage numbered among the stages the run plans.
class StderrProgress : public ProgressObserver {
 public:
  explicit StderrProgress(const PipelineOptions& options)
      : stages_(PlannedStages(options)), line_(std::cerr, ::isatty(2)) {}
  bool OnProgress(absl::string_view stage, double fraction, absl::string_view) override {
    std::lock_guard<std::mutex> lock(mu_);
    const auto it = std::find(stages_.begin() + index_, stages_.end(), stage);
    if (it != stages_.end()) index_ = static_cast<int>(it - stages_.begin());
    line_.Show("", index_ + 1, static_cast<int>(stages_.size()), stage, fraction);
    return true;
  }
  void Finish() {
    std::lock_guard<std::mutex> lock(mu_);
    line_.Finish("");
  }

 private:
  const std::vector<std::string> stages_;
  std::mutex mu_;
  int index_ = 0;
  ProgressLine line_;
};

// The run's summary on `out`: what each stage made.
void PrintRun(const PipelineReport& r, std::ostream& out);

}  // namespace

absl::Status RunSurface(const PipelineOptions& options, std::ostream& out) {
  StderrProgress progress(options);
  absl::StatusOr<PipelineReport> run = RunPipeline(options, Progress(&progress, ""));
  progress.Finish();
  SM_ASSIGN_OR_RETURN(PipelineReport r, std::move(run));
  PrintRun(r, out);
  return absl::OkStatus();
}

absl::Status RunMergeCommand(const std::string& plan_dir, const std::string& output_dir,
                             std::ostream& out) {
  SM_ASSIGN_OR_RETURN(const BrickPlan plan, ReadBrickPlan(plan_dir));
  ParameterBuilder builder;
  SM_RETURN_IF_ERROR(builder.AddJson(plan.parameters, PlanFile(plan_dir)));
  SM_ASSIGN_OR_RETURN(const PipelineOptions options, builder.Build());
  StderrProgress progress(options);
  MergeSummary summary;
  absl::StatusOr<PipelineReport> run =
      MergeBricks(plan_dir, output_dir, Progress(&progress, ""), &summary);
  progress.Finish();
  SM_ASSIGN_OR_RETURN(PipelineReport r, std::move(run));
  out << absl::StrFormat("bricks      %d joined (%d bytes) in %.2f s: %d sheet voxels\n",
                         summary.bricks, summary.brick_bytes, summary.join_seconds,
                         summary.sheet_voxels);
  PrintRun(r, out);
  return absl::OkStatus();
}

namespace {

void PrintRun(const PipelineReport& r, std::ostream& out) {
  if (r.sheetness) {
    out << absl::StrFormat("sheet       %d voxels found by their sheetness (%d seeds)\n",
                           r.sheet_voxels, r.sheetness->seeds);
  } else {
    out << absl::StrFormat("sheet       %d voxels of %s\n", r.sheet_voxels,
                           r.options.input.selection.ToString());
  }
  if (r.extraction) {
    for (const ExtractionStep& s : r.extraction->steps) {
      if (!s.ran) {
        out << absl::StrFormat("  %-13s skipped\n", s.name);
        continue;
      }
      out << absl::StrFormat("  %-13s voxels %d -> %d (+%d -%d), objects %d -> %d, %.2f s\n",
                             s.name, s.voxels_before, s.voxels_after, s.added, s.removed,
                             s.objects_before, s.objects_after, s.seconds);
    }
    out << absl::StrFormat("model       %d pieces, %d voxels (M = %d)\n", r.extraction->pieces,
                           r.extraction->model_voxels, r.extraction->min_object_voxels);
  }
  out << absl::StrFormat("meshed set  %d voxels, t̄ = %.2f, %d components\n",
                         r.extraction ? r.extraction->model_voxels : r.sheet_voxels,
                         r.thickness.mean, r.components);
  if (r.radius_choice) {
    out << "r search   ";
    for (const RadiusTrial& t : r.radius_choice->trials) {
      if (t.scored) {
        out << absl::StrFormat(" r=%g:%.3f(%d)", t.radius, t.similarity, t.triangles);
      } else {
        out << absl::StrFormat(" r=%g:(%d)", t.radius, t.triangles);
      }
    }
    out << absl::StrFormat(
        "\n            chose r = %g%s\n", r.radius_choice->radius,
        r.radius_choice->target_reached
            ? ""
            : absl::StrCat(" (target not reached: ", r.radius_choice->message, ")"));
  }
  const SurfaceStats& m = *r.surface;
  out << absl::StrFormat(
      "surface     r = %g: %d generators (%d Lloyd steps), %d vertices, %d triangles, "
      "element size %.2f voxels\n",
      r.options.surface.scvd.radius_voxels, m.generators, m.lloyd_iterations, m.vertices,
      m.triangles, m.element_size_voxels);
  out << absl::StrFormat(
      "topology    %d boundary loops, %d non-manifold edges, %d connected parts; %d components "
      "(%d voxels) too small for a triangle\n",
      m.topology.boundary_loops, m.topology.nonmanifold_edges, m.topology.connected_parts,
      m.skipped_components, m.skipped_voxels);
  if (m.mesher_choice) {
    const MesherChoiceStats& c = *m.mesher_choice;
    out << absl::StrFormat(
        "mesher      %s (auto): the mid-surface scores %.4f, the SCVD %.4f; %s\n",
        c.kept_mid ? "midsurface" : "scvd", c.mid_similarity, c.scvd_similarity,
        c.kept_mid ? "its junctions are at the rock's angles"
                   : absl::StrFormat("more than %.2f above the mid-surface's", c.margin));
  }
  if (m.apertures) {
    const FaceApertureStats& a = *m.apertures;
    out << absl::StrFormat(
        "apertures   per face, beside the fitted thickness: %d junction faces at their own "
        "sheet's (%d lowered, %d raised), %d covered faces given their sheet's, %d over holes\n",
        a.junction, a.junction_lowered, a.junction_raised, a.covered, a.holes);
  }
  if (r.grey_apertures) {
    const GreyApertureStats& g = *r.grey_apertures;
    out << absl::StrFormat(
        "grey levels rock %.6g%s, void %.6g%s, noise %.3g (contrast to noise %.1f)\n",
        g.levels.rock, g.levels.rock_measured ? "" : " (given)", g.levels.void_level,
        g.levels.void_measured ? "" : " (given)", g.levels.noise, g.levels.cnr());
    if (g.measured) {
      out << absl::StrFormat(
          "            aperture from the grey levels: mean %.3g voxels over %d faces (counted "
          "from voxels: %.3g), ± %.2g a face\n",
          g.mean_voxels, g.faces, g.counted_mean_voxels, g.uncertainty_voxels);
    } else {
      out << "            apertures counted from voxels: " << g.levels.problem << "\n";
    }
  }
  if (r.representation && !r.representation->pieces.empty()) {
    // Each piece as what, and why (the largest ten; the report lists them all).
    std::vector<const PieceRepresentation*> largest;
    for (const PieceRepresentation& p : r.representation->pieces) largest.push_back(&p);
    std::stable_sort(largest.begin(), largest.end(),
                     [](const auto* a, const auto* b) { return a->voxels > b->voxels; });
    if (largest.size() > 10) largest.resize(10);
    out << absl::StrFormat("pieces as   %d of %d meshed as closed surfaces (piece: as what, why)\n",
                           r.representation->bodies, r.representation->pieces.size());
    for (const PieceRepresentation* p : largest) {
      out << absl::StrFormat("            %d%s: %s, %s\n", p->piece,
                             p->part_of >= 0 ? absl::StrCat(" (a lens of ", p->part_of, ")") : "",
                             p->body ? absl::StrFormat("body (equivalent aperture %.3g voxels)",
                                                       p->equivalent_aperture)
                                     : "sheet",
                             p->reason);
    }
  }
  const SimilarityReport& sim = *r.similarity;
  out << absl::StrFormat("similarity  %.4f (C_in %d, C_out %d, C_image %d), Dice %.4f",
                         sim.score.similarity, sim.score.c_in, sim.score.c_out, sim.score.c_image,
                         sim.score.dice);
  if (sim.score.hausdorff >= 0)
    out << absl::StrFormat(", Hausdorff %.2f voxels", sim.score.hausdorff);
  out << absl::StrFormat("; other prism model %.4f\n", sim.shell_similarity);
  if (sim.raw) {
    out << absl::StrFormat(
        "            against the raw phase: %.4f (C_in %d, C_out %d, C_image %d)\n",
        sim.raw->similarity, sim.raw->c_in, sim.raw->c_out, sim.raw->c_image);
  }
  if (r.extraction) {
    out << "pieces      (piece: voxels, dip/dip direction, mean aperture)\n";
    for (size_t i = 0; i < r.geology.size() && i < 10; ++i) {
      const PieceGeology& g = r.geology[i];
      out << absl::StrFormat("            %d: %d voxels, %.0f/%03.0f, %.2f\n", g.piece, g.voxels,
                             g.dip_degrees, g.dip_direction_degrees, g.mean_aperture);
    }
  }
  if (!sim.grid.empty()) {
    out << "grid models";
    for (const GridFigure& g : sim.grid) {
      out << absl::StrFormat("  k=%d: %.4f (%d cells)", g.rate, g.similarity, g.grid_quantity);
    }
    out << "\n";
    if (const std::optional<std::string> w = sim.FloorWarning())
      out << "  warning   " << *w << "\n";
  }
  if (r.volume_mesh) PrintVolumeMesh(*r.volume_mesh, out);
  PrintSplit(r.volume_split, out);
  if (r.flow) {
    const PermeabilityResult& k = *r.flow;
    out << absl::StrFormat(
        "permeability  k_xx %.4g  k_yy %.4g  k_zz %.4g m² (%.4g / %.4g / %.4g darcy); principal "
        "%.4g, %.4g, %.4g m²\n",
        k.tensor[0][0], k.tensor[1][1], k.tensor[2][2], k.tensor[0][0] / kSquareMetresPerDarcy,
        k.tensor[1][1] / kSquareMetresPerDarcy, k.tensor[2][2] / kSquareMetresPerDarcy,
        k.principal[0], k.principal[1], k.principal[2]);
    out << absl::StrFormat("              permeameters %.4g / %.4g / %.4g m²", k.permeameter[0],
                           k.permeameter[1], k.permeameter[2]);
    if (r.flow_image) {
      out << absl::StrFormat("; the image's %.4g / %.4g / %.4g (mesh / image %.3f / %.3f / %.3f)",
                             r.flow_image->tensor[0][0], r.flow_image->tensor[1][1],
                             r.flow_image->tensor[2][2], r.flow_image->mesh_to_image[0],
                             r.flow_image->mesh_to_image[1], r.flow_image->mesh_to_image[2]);
    } else if (!r.flow_image_skipped.empty()) {
      out << "; the image's reference skipped: " << r.flow_image_skipped;
    }
    out << "\n";
    out << absl::StrFormat(
        "              the sheets carry %.0f%% / %.0f%% / %.0f%% of the flux; %d sheet faces, "
        "%d unknowns, CG %d/%d/%d iterations (residual %.1e)%s\n",
        100 * k.fracture_share[0], 100 * k.fracture_share[1], 100 * k.fracture_share[2],
        k.sheet_faces, k.unknowns, k.iterations[0], k.iterations[1], k.iterations[2], k.residual,
        k.note.empty() ? "" : "; " + k.note);
  }
  out << "time       ";
  for (const StageTime& t : r.timings) out << absl::StrFormat(" %s %.2fs", t.stage, t.seconds);
  out << "\n";
  const std::string& dir = r.options.output.dir;
  if (!dir.empty()) out << "wrote       " << dir << "/{";
  for (size_t i = 0; i < r.files.size(); ++i) out << (i ? "," : "") << r.files[i];
  if (!dir.empty()) out << "}\n";
}

}  // namespace

absl::Status RunVolume(const std::string& surface, const VolumeInfo& box,
                       const PipelineOptions& options, std::ostream& out) {
  PipelineReport report;
  report.options = options;
  report.volume = box;
  report.volume.path = surface;
  const absl::Time start = absl::Now();
  SM_ASSIGN_OR_RETURN(TriangleMesh mesh, ReadMesh(surface, box.placement));
  VolumeMeshOptions vo = options.volume;
  if (!options.output.dir.empty() && MakeDirs(options.output.dir).ok()) {
    vo.tetgen.failed_plc_path = options.output.dir + "/tetgen_failed.poly";
  }
  SM_ASSIGN_OR_RETURN(VolumeMeshResult r, BuildVolumeMesh(mesh, box.dims, box.placement, vo));
  report.timings.push_back({"volume", absl::ToDoubleSeconds(absl::Now() - start)});
  SM_RETURN_IF_ERROR(MakeDirs(options.output.dir));
  const std::string dir = options.output.dir;
  SplitStats split;
  SM_RETURN_IF_ERROR(WriteVolumeFiles(dir, r.mesh, options.output, &report.files, nullptr, &split));
  report.volume_mesh = static_cast<const VolumeMeshStats&>(r);
  if (options.output.split) report.volume_split = split;
  report.files.push_back("volume_report.json");
  SM_RETURN_IF_ERROR(WriteFileAtomically(dir + "/volume_report.json", report.ToJson()));
  PrintVolumeMesh(*report.volume_mesh, out);
  PrintSplit(report.volume_split, out);
  out << "wrote       " << dir << "\n";
  return absl::OkStatus();
}

absl::Status RunScore(const ScoreCommandOptions& options, std::ostream& out) {
  if (!options.closed && options.mesh_path.size() > 4 &&
      options.mesh_path.substr(options.mesh_path.size() - 4) == ".obj") {
    return absl::InvalidArgumentError(absl::StrCat(
        options.mesh_path, ": OBJ carries no thickness; give --closed or score the PLY"));
  }
  SM_ASSIGN_OR_RETURN(SheetPhase phase, LoadSheetPhase(options.input));
  SM_ASSIGN_OR_RETURN(TriangleMesh mesh, ReadMesh(options.mesh_path, phase.info.placement));
  VoxelSet model;
  if (options.closed) {
    SM_ASSIGN_OR_RETURN(model, VoxelizeClosedSurface(mesh, phase.info.dims));
  } else if (mesh.face_thickness_voxels.size() == mesh.faces.size()) {
    // A sheetmesh surface: its sheets' prisms and its bodies' insides (the PLY's `body`).
    SM_ASSIGN_OR_RETURN(model, VoxelizeMesh(mesh, phase.info.dims));
  } else {
    return absl::InvalidArgumentError(
        absl::StrCat(options.mesh_path,
                     ": has no per-face thickness to build sheet prisms from; give "
                     "--closed to score a closed surface by the volume it encloses"));
  }
  SimilarityScore s = ScoreModel(model, phase.sheet);
  if (options.hausdorff) {
    SM_ASSIGN_OR_RETURN(s.hausdorff, HausdorffDistance(model, phase.sheet));
  }
  if (options.json) {
    nlohmann::json j = {{"mesh", options.mesh_path},
                        {"volume", phase.info.path},
                        {"triangles", mesh.num_faces()},
                        {"similarity", s.similarity},
                        {"c_in", s.c_in},
                        {"c_out", s.c_out},
                        {"c_image", s.c_image},
                        {"dice", s.dice},
                        {"hausdorff_voxels", s.hausdorff}};
    out << JsonText(j, 2) << "\n";
    return absl::OkStatus();
  }
  out << absl::StrFormat(
      "%s: %d triangles, similarity %.4f (C_in %d, C_out %d, C_image %d), Dice %.4f, Hausdorff "
      "%.2f voxels\n",
      options.mesh_path, mesh.num_faces(), s.similarity, s.c_in, s.c_out, s.c_image, s.dice,
      s.hausdorff);
  return absl::OkStatus();
}

}  // namespace sheetmesh
