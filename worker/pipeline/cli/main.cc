// sheetmesh-pipeline: the offline pipeline, no server needed.
//   sheetmesh-pipeline info VOLUME [selection flags] [--json]
//   sheetmesh-pipeline phantom -o FILE [--preset sample|paper] [phantom flags]
#include <iostream>
#include <set>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/reflection.h"
#include "absl/flags/usage.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "worker/pipeline/cli/info_command.h"
#include "worker/pipeline/cli/phantom_command.h"
#include "worker/pipeline/cli/surface_command.h"
#include "worker/pipeline/core/file_util.h"
#include "worker/pipeline/core/huge_pages.h"
#include "worker/pipeline/core/status_macros.h"
#include "worker/pipeline/run/pipeline_config.h"

// Volume input.
ABSL_FLAG(std::string, format, "", "volume format: raw, tiff, nrrd, vdb (default: by extension)");
ABSL_FLAG(std::string, dims, "",
          "raw volumes: NXxNYxNZ (default: from a name like a_64x64x32_u8.raw); phantom: its size");
ABSL_FLAG(std::string, dtype, "", "raw volumes: uint8, uint16 or float32");
ABSL_FLAG(std::string, byte_order, "little", "raw volumes: little or big");
ABSL_FLAG(int64_t, header_bytes, 0, "raw volumes: bytes to skip before the voxels");
ABSL_FLAG(std::string, vdb_grid, "", "vdb volumes: grid name (default: first scalar grid)");
ABSL_FLAG(std::string, spacing, "", "voxel size SX,SY,SZ overriding the file's");
ABSL_FLAG(std::string, origin, "", "origin OX,OY,OZ overriding the file's");
ABSL_FLAG(std::string, unit, "", "length unit overriding the file's (mm, um, ...)");
ABSL_FLAG(int64_t, max_voxels, int64_t{1} << 37, "refuse volumes with more voxels");
ABSL_FLAG(std::string, labels, "", "sheet phase: voxel values, e.g. 255 or 2,3");
ABSL_FLAG(std::string, window, "", "sheet phase: intensity window LO:HI");
ABSL_FLAG(std::string, mask, "", "rock mask volume (non-zero = rock), same dims");
ABSL_FLAG(std::string, mask_labels, "", "rock mask: values that are rock (default non-zero)");
// info
ABSL_FLAG(bool, json, false, "print JSON");
ABSL_FLAG(int, connectivity, 6, "component connectivity: 6, 18 or 26");
ABSL_FLAG(int, largest, 10, "component sizes to list");
// surface, score
ABSL_FLAG(double, r, 7.0, "surface: SCVD cell radius r in voxels (formula 3)");
ABSL_FLAG(double, target_similarity, -1,
          "surface: search the largest r reaching this similarity (paper: 0.6)");
ABSL_FLAG(bool, search_best, false, "surface: search the r of best similarity");
ABSL_FLAG(double, r_min, 2, "surface: smallest r of a search");
ABSL_FLAG(double, r_max, 0, "surface: largest r of a search (0: a quarter of the largest extent)");
ABSL_FLAG(int64_t, generators, 0, "surface: total generator count instead of formula 3");
ABSL_FLAG(double, thickness, 0, "surface: mean thickness t in voxels for formula 3 (0: measured)");
ABSL_FLAG(int, lloyd_max_iter, 20, "surface: Lloyd steps at most");
ABSL_FLAG(double, lloyd_tol, 1e-3, "surface: Lloyd stop when the energy changes less (relative)");
ABSL_FLAG(double, fold_angle, 50,
          "surface: reject triangles folding onto kept ones below this dihedral angle");
ABSL_FLAG(std::string, method, "extended",
          "surface: extended (rim strip, centroid vertices, thickness along the normal) or paper "
          "(the plain reading)");
ABSL_FLAG(std::string, placement, "",
          "surface: vertex placement generator or centroid (default: the method's)");
ABSL_FLAG(std::string, thickness_measure, "",
          "surface: axis_runs or normal (default: the method's)");
ABSL_FLAG(std::string, rim, "", "surface: true/false, close the rim band (default: the method's)");
ABSL_FLAG(std::string, similarity_model, "face",
          "surface: face (one thickness per triangle) or vertex (linear shell)");
ABSL_FLAG(bool, hausdorff, true, "surface/score: also compute the symmetric Hausdorff distance");
ABSL_FLAG(std::string, grid_rates, "2,3,4", "surface: grid-model baselines to score (empty: none)");
ABSL_FLAG(std::string, formats, "ply,vtp,obj", "surface: mesh files to write");
ABSL_FLAG(bool, closed, false, "score: the mesh is a closed surface; score the volume it encloses");
// run (feature extraction; every flag here overrides --config)
ABSL_FLAG(std::string, config, "",
          "run/surface: JSON config file with any parameter (flags override it)");
ABSL_FLAG(bool, refine, true, "run: refine (closing/opening)");
ABSL_FLAG(int, refine_close, 1, "run: closing radius in voxels");
ABSL_FLAG(int, refine_open, 0, "run: opening radius in voxels");
ABSL_FLAG(bool, detect, true, "run: detect potential objects by extending");
ABSL_FLAG(double, detect_t, 1.5, "run: t of formula 4 for detection");
ABSL_FLAG(double, detect_R, 7, "run: R of formula 4 for detection");
ABSL_FLAG(int, detect_rounds, 1, "run: detection rounds");
ABSL_FLAG(uint64_t, M, 0, "run: volume criterion M in voxels (0: three separation cells)");
ABSL_FLAG(bool, separate, true, "run: separate crossings (Algorithm 2)");
ABSL_FLAG(double, r_sep, 5, "run: SCVD radius for separation and extending");
ABSL_FLAG(double, D_ang, 150, "run: dihedral angle threshold of Algorithm 2, degrees");
ABSL_FLAG(bool, remove_minor, true, "run: remove pieces below M");
ABSL_FLAG(bool, recover, true, "run: recover cut gaps by extending within the image");
ABSL_FLAG(double, recover_t, 1.5, "run: t of formula 4 for recovery");
ABSL_FLAG(double, recover_R, 7, "run: R of formula 4 for recovery");
ABSL_FLAG(int, recover_rounds, 10, "run: recovery rounds at most");
// volume mesh (run, surface --volume_mesh, volume)
ABSL_FLAG(bool, volume_mesh, false,
          "run/surface: also tetrahedralize the box with the sheets inside (TetGen)");
ABSL_FLAG(double, tet_ratio, 1.5,
          "volume: TetGen radius-edge ratio bound (-q; 0: no quality bound)");
ABSL_FLAG(double, tet_min_dihedral, 10, "volume: smallest dihedral angle asked of TetGen, degrees");
ABSL_FLAG(double, tet_max_volume, 0,
          "volume: largest tetrahedron volume, physical units^3 (0: none)");
ABSL_FLAG(bool, tet_steiner, false,
          "volume: allow TetGen to add points on the sheets and box (default false: -Y, TetGen "
          "keeps each sheet triangle one face and the box faces are seeded)");
ABSL_FLAG(double, tet_time_limit, 600, "volume: seconds before TetGen is killed");
ABSL_FLAG(double, tet_memory_gb, 8, "volume: memory limit of TetGen, GiB");
ABSL_FLAG(std::string, tetgen, "tetgen", "volume: the TetGen program");
ABSL_FLAG(
    double, flip_fold, 15,
    "volume: flip sheet edges between nearly coplanar triangles (normals within this many degrees) "
    "where that gives better triangles; 0: keep the sheet triangles as given");
ABSL_FLAG(double, overlap, 0.5,
          "volume: drop a sheet's rim triangle that runs within this many voxels of another "
          "sheet, nearly parallel to it (it forces slivers); 0: keep them");
ABSL_FLAG(double, wedge, 12,
          "volume: move a sheet vertex up to --wedge_voxels off another sheet face's plane where "
          "its edge runs within this many degrees of the face from a shared corner; 0: never");
ABSL_FLAG(double, wedge_voxels, 1, "volume: the farthest a vertex moves to open a wedge (--wedge)");
ABSL_FLAG(double, lattice, 0.85,
          "volume: seed TetGen with a graded body-centred cubic lattice off the sheets, spaced "
          "this many times the sheets' median edge (smaller: more tetrahedra, better shaped); "
          "0: none, TetGen places the points");
ABSL_FLAG(int, improve_passes, 4,
          "volume: rounds of flips, smoothing and insertion on TetGen's output (0: none)");
ABSL_FLAG(double, improve_target, 50,
          "volume: tetrahedra below this smallest dihedral angle (degrees) are improved");
ABSL_FLAG(double, improve_insert, 50,
          "volume: tetrahedra below this angle after the flips get a new vertex beside them "
          "(degrees; 0: none)");
ABSL_FLAG(double, improve_split, 15,
          "volume: a tetrahedron below this angle that no new vertex off the sheets mends may "
          "get one on a sheet face or edge beside it, splitting that face (degrees; 0: every "
          "sheet triangle stays one face)");
ABSL_FLAG(double, improve_floor, 20,
          "volume: smoothing for the mean never lowers a vertex's worst tetrahedron below this");
ABSL_FLAG(double, improve_radius_weight, 0.5,
          "volume: smoothing raises the mean of (1-w) x smallest dihedral angle + w x 70.53 "
          "degrees x radius aspect (0: the dihedral angle alone)");
ABSL_FLAG(bool, repair, false, "volume: drop the smaller of each pair of clashing sheet triangles");
ABSL_FLAG(std::string, volume_formats, "vtu,msh,inp", "volume: files to write");
ABSL_FLAG(std::string, box, "", "volume: the box NXxNYxNZ in voxels, when no --volume is given");
ABSL_FLAG(std::string, volume, "",
          "volume: the image whose box, spacing and origin the mesh fills");
// phantom
ABSL_FLAG(std::string, o, "", "output path (phantom: the volume file; surface: the folder)");
ABSL_FLAG(std::string, out_format, "raw",
          "phantom output: raw, tiff, tiff-folder, nrrd, nrrd-gzip, vdb");
ABSL_FLAG(std::string, preset, "",
          "phantom preset: sample (the demo volume) or paper (1012x1024x931)");
ABSL_FLAG(std::string, phantom_dims, "", "phantom dims NXxNYxNZ");
ABSL_FLAG(uint64_t, seed, 1, "phantom seed");
ABSL_FLAG(int, sheets, -1, "phantom sheets (default: the preset's)");
ABSL_FLAG(double, aperture, -1, "phantom mean aperture in voxels (default: the preset's)");
ABSL_FLAG(int, specks, -2, "phantom specks (-1: one per 20^3 voxels; default: the preset's)");
ABSL_FLAG(std::string, truth, "", "phantom ground truth JSON (default: OUTPUT.truth.json)");

namespace sheetmesh {
namespace {

constexpr char kUsage[] =
    "sheetmesh-pipeline COMMAND [ARGS] [FLAGS]\n\n"
    "commands:\n"
    "  info VOLUME             dims, sheet voxels, thickness and components of a volume\n"
    "  surface VOLUME -o DIR   mesh the sheets: --r R, or --target-similarity S, or --search-best\n"
    "  run VOLUME -o DIR       extract the major sheets (Fig. 3), then mesh and score them;\n"
    "                          --volume_mesh adds the TetGen volume mesh; --config FILE sets\n"
    "                          any parameter, flags override it\n"
    "  volume SURFACE.ply -o DIR  tetrahedralize the box (--volume VOL or --box) around a surface\n"
    "  score VOLUME MESH       score a .ply/.obj against the volume (--closed for closed "
    "surfaces)\n"
    "  phantom -o FILE         write a synthetic rock volume and its ground truth\n"
    "  convert VOLUME -o FILE  copy a volume into --out_format (raw, tiff, nrrd, vdb, ...)\n\n"
    "Flags may be written with dashes or underscores (--target-similarity).\n"
    "Run with --help for every flag.";

absl::StatusOr<Vec3> ParseVec3(const std::string& flag, const std::string& text) {
  std::vector<std::string> parts = absl::StrSplit(text, ',');
  Vec3 v;
  if (parts.size() != 3) {
    return absl::InvalidArgumentError(
        absl::StrCat("--", flag, "=", text, " must be three comma-separated numbers"));
  }
  for (int k = 0; k < 3; ++k) {
    if (!absl::SimpleAtod(parts[k], &v[k])) {
      return absl::InvalidArgumentError(
          absl::StrCat("--", flag, "=", text, ": '", parts[k], "' is not a number"));
    }
  }
  return v;
}

absl::StatusOr<Dims> ParseDims(const std::string& flag, const std::string& text) {
  std::vector<std::string> parts = absl::StrSplit(text, 'x');
  Dims d;
  if (parts.size() != 3 || !absl::SimpleAtoi(parts[0], &d.nx) ||
      !absl::SimpleAtoi(parts[1], &d.ny) || !absl::SimpleAtoi(parts[2], &d.nz)) {
    return absl::InvalidArgumentError(
        absl::StrCat("--", flag, "=", text, " must look like 512x512x400"));
  }
  return d;
}

absl::StatusOr<SheetInput> InputFromFlags(const std::string& path) {
  SheetInput in;
  in.path = path;
  OpenOptions& o = in.open;
  o.format = absl::GetFlag(FLAGS_format);
  if (!absl::GetFlag(FLAGS_dims).empty()) {
    SM_ASSIGN_OR_RETURN(o.raw_dims, ParseDims("dims", absl::GetFlag(FLAGS_dims)));
  }
  if (!absl::GetFlag(FLAGS_dtype).empty()) {
    SM_ASSIGN_OR_RETURN(o.raw_dtype, ParseDType(absl::GetFlag(FLAGS_dtype)));
  }
  SM_ASSIGN_OR_RETURN(o.raw_byte_order, ParseByteOrder(absl::GetFlag(FLAGS_byte_order)));
  o.raw_header_bytes = absl::GetFlag(FLAGS_header_bytes);
  o.vdb_grid = absl::GetFlag(FLAGS_vdb_grid);
  if (!absl::GetFlag(FLAGS_spacing).empty()) {
    SM_ASSIGN_OR_RETURN(o.spacing, ParseVec3("spacing", absl::GetFlag(FLAGS_spacing)));
  }
  if (!absl::GetFlag(FLAGS_origin).empty()) {
    SM_ASSIGN_OR_RETURN(o.origin, ParseVec3("origin", absl::GetFlag(FLAGS_origin)));
  }
  o.unit = absl::GetFlag(FLAGS_unit);
  o.limits.max_voxels = absl::GetFlag(FLAGS_max_voxels);
  if (!absl::GetFlag(FLAGS_labels).empty() && !absl::GetFlag(FLAGS_window).empty()) {
    return absl::InvalidArgumentError("give either --labels or --window, not both");
  }
  if (!absl::GetFlag(FLAGS_labels).empty()) {
    SM_ASSIGN_OR_RETURN(in.selection, ParsePhaseSelection("labels=" + absl::GetFlag(FLAGS_labels)));
  } else if (!absl::GetFlag(FLAGS_window).empty()) {
    SM_ASSIGN_OR_RETURN(in.selection, ParsePhaseSelection("window=" + absl::GetFlag(FLAGS_window)));
  }
  in.mask_path = absl::GetFlag(FLAGS_mask);
  if (!absl::GetFlag(FLAGS_mask_labels).empty()) {
    SM_ASSIGN_OR_RETURN(in.mask_selection,
                        ParsePhaseSelection("labels=" + absl::GetFlag(FLAGS_mask_labels)));
  }
  return in;
}

absl::Status Info(const std::vector<std::string>& args) {
  if (args.size() != 1) return absl::InvalidArgumentError("usage: info VOLUME [flags]");
  InfoOptions options;
  SM_ASSIGN_OR_RETURN(options.input, InputFromFlags(args[0]));
  SM_ASSIGN_OR_RETURN(options.connectivity, ParseConnectivity(absl::GetFlag(FLAGS_connectivity)));
  options.largest_components = absl::GetFlag(FLAGS_largest);
  options.json = absl::GetFlag(FLAGS_json);
  return RunInfo(options, std::cout);
}

absl::Status Phantom(const std::vector<std::string>& args) {
  if (!args.empty()) return absl::InvalidArgumentError("usage: phantom -o FILE [flags]");
  PhantomCommandOptions options;
  const std::string preset = absl::GetFlag(FLAGS_preset);
  if (preset == "sample") {
    options.phantom = SamplePhantomOptions();
  } else if (preset == "paper") {
    options.phantom.dims = {1012, 1024, 931};
    options.phantom.num_sheets = 6;
    options.phantom.num_specks = -1;
  } else if (!preset.empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat("--preset=", preset, " is not known; use sample or paper"));
  }
  // --dims is the natural spelling for the volume being made; --phantom_dims too.
  if (!absl::GetFlag(FLAGS_phantom_dims).empty() && !absl::GetFlag(FLAGS_dims).empty()) {
    return absl::InvalidArgumentError("give the phantom's size once: --dims or --phantom_dims");
  }
  if (!absl::GetFlag(FLAGS_phantom_dims).empty()) {
    SM_ASSIGN_OR_RETURN(options.phantom.dims,
                        ParseDims("phantom_dims", absl::GetFlag(FLAGS_phantom_dims)));
  } else if (!absl::GetFlag(FLAGS_dims).empty()) {
    SM_ASSIGN_OR_RETURN(options.phantom.dims, ParseDims("dims", absl::GetFlag(FLAGS_dims)));
  }
  if (!absl::GetFlag(FLAGS_dtype).empty()) {
    SM_ASSIGN_OR_RETURN(options.phantom.dtype, ParseDType(absl::GetFlag(FLAGS_dtype)));
  }
  if (preset.empty() || absl::GetFlag(FLAGS_seed) != 1) {
    options.phantom.seed = absl::GetFlag(FLAGS_seed);
  }
  if (absl::GetFlag(FLAGS_sheets) >= 0) options.phantom.num_sheets = absl::GetFlag(FLAGS_sheets);
  if (absl::GetFlag(FLAGS_aperture) > 0) {
    options.phantom.aperture_voxels = absl::GetFlag(FLAGS_aperture);
  }
  if (absl::GetFlag(FLAGS_specks) >= -1) options.phantom.num_specks = absl::GetFlag(FLAGS_specks);
  options.output = absl::GetFlag(FLAGS_o);
  if (options.output.empty()) return absl::InvalidArgumentError("phantom needs -o FILE");
  SM_ASSIGN_OR_RETURN(options.format, ParseVolumeFormat(absl::GetFlag(FLAGS_out_format)));
  options.truth_path = absl::GetFlag(FLAGS_truth);
  return RunPhantom(options, std::cout);
}

absl::Status Convert(const std::vector<std::string>& args) {
  if (args.size() != 1)
    return absl::InvalidArgumentError("usage: convert VOLUME -o FILE --out_format=F");
  SM_ASSIGN_OR_RETURN(SheetInput in, InputFromFlags(args[0]));
  SM_ASSIGN_OR_RETURN(VolumeFormat format, ParseVolumeFormat(absl::GetFlag(FLAGS_out_format)));
  if (absl::GetFlag(FLAGS_o).empty()) return absl::InvalidArgumentError("convert needs -o FILE");
  return RunConvert(in.path, in.open, absl::GetFlag(FLAGS_o), format, std::cout);
}

// Flags named on the command line (recorded before parsing), so that only they override
// a config file.
std::set<std::string>& GivenFlags() {
  static std::set<std::string> given;
  return given;
}

bool Given(const std::string& flag) { return GivenFlags().count(flag) > 0; }

// The volume-mesh flags given on the command line.
absl::Status VolumeFromFlags(PipelineOptions* o) {
  TetgenOptions& t = o->volume.tetgen;
  if (Given("tet_ratio")) t.max_radius_edge_ratio = absl::GetFlag(FLAGS_tet_ratio);
  if (Given("tet_min_dihedral")) t.min_dihedral_degrees = absl::GetFlag(FLAGS_tet_min_dihedral);
  if (Given("tet_max_volume")) t.max_volume = absl::GetFlag(FLAGS_tet_max_volume);
  if (Given("tet_steiner")) t.steiner_on_sheets = absl::GetFlag(FLAGS_tet_steiner);
  if (Given("tet_time_limit")) t.time_limit_seconds = absl::GetFlag(FLAGS_tet_time_limit);
  if (Given("tet_memory_gb")) {
    t.memory_limit_bytes = static_cast<uint64_t>(absl::GetFlag(FLAGS_tet_memory_gb) * (1ull << 30));
  }
  if (Given("tetgen")) t.program = absl::GetFlag(FLAGS_tetgen);
  if (Given("repair")) o->volume.plc.repair = absl::GetFlag(FLAGS_repair);
  if (Given("flip_fold")) o->volume.plc.flip_fold_degrees = absl::GetFlag(FLAGS_flip_fold);
  if (Given("overlap")) o->volume.plc.overlap_voxels = absl::GetFlag(FLAGS_overlap);
  if (Given("wedge")) o->volume.plc.wedge_degrees = absl::GetFlag(FLAGS_wedge);
  if (Given("wedge_voxels")) o->volume.plc.wedge_voxels = absl::GetFlag(FLAGS_wedge_voxels);
  if (Given("lattice")) o->volume.plc.lattice = absl::GetFlag(FLAGS_lattice);
  TetImproveOptions& im = o->volume.improve;
  if (Given("improve_passes")) im.passes = absl::GetFlag(FLAGS_improve_passes);
  if (Given("improve_target")) im.target_degrees = absl::GetFlag(FLAGS_improve_target);
  if (Given("improve_insert")) im.insert_below_degrees = absl::GetFlag(FLAGS_improve_insert);
  if (Given("improve_floor")) im.smoothing_floor_degrees = absl::GetFlag(FLAGS_improve_floor);
  if (Given("improve_split")) im.split_sheets_below_degrees = absl::GetFlag(FLAGS_improve_split);
  if (Given("improve_radius_weight")) {
    im.radius_weight = absl::GetFlag(FLAGS_improve_radius_weight);
  }
  if (Given("volume_formats")) {
    o->output.vtu = o->output.msh = o->output.inp = false;
    for (absl::string_view f :
         absl::StrSplit(absl::GetFlag(FLAGS_volume_formats), ',', absl::SkipEmpty())) {
      if (f == "vtu") {
        o->output.vtu = true;
      } else if (f == "msh") {
        o->output.msh = true;
      } else if (f == "inp") {
        o->output.inp = true;
      } else {
        return absl::InvalidArgumentError(
            absl::StrCat("--volume_formats: '", f, "' is not vtu, msh or inp"));
      }
    }
  }
  return absl::OkStatus();
}

// Defaults, then --config, then every flag given on the command line.
absl::StatusOr<PipelineOptions> PipelineFromFlags(const std::string& volume, bool extract) {
  PipelineOptions o;
  o.extract = extract;
  SM_ASSIGN_OR_RETURN(SheetInput input, InputFromFlags(volume));
  if (!absl::GetFlag(FLAGS_config).empty()) {
    SM_ASSIGN_OR_RETURN(std::string text, ReadFileToString(absl::GetFlag(FLAGS_config)));
    SM_RETURN_IF_ERROR(ApplyPipelineConfig(text, absl::GetFlag(FLAGS_config), &o));
  }
  // The volume's path always comes from the command line; the rest of the input only
  // where a flag says so.
  o.input.path = input.path;
  for (const char* f : {"format", "dims", "dtype", "byte_order", "header_bytes", "vdb_grid",
                        "spacing", "origin", "unit", "max_voxels"}) {
    if (Given(f)) {
      o.input.open = input.open;
      break;
    }
  }
  if (Given("labels") || Given("window")) o.input.selection = input.selection;
  if (Given("mask")) o.input.mask_path = input.mask_path;
  if (Given("mask_labels")) o.input.mask_selection = input.mask_selection;

  if (Given("method")) {
    const std::string method = absl::GetFlag(FLAGS_method);
    if (method == "paper") {
      o.surface = SurfaceOptions::Paper();
    } else if (method != "extended") {
      return absl::InvalidArgumentError(
          absl::StrCat("--method=", method, " is not known; use extended or paper"));
    }
  }
  ScvdOptions& scvd = o.surface.scvd;
  if (Given("r")) scvd.radius_voxels = absl::GetFlag(FLAGS_r);
  if (Given("seed")) scvd.seed = absl::GetFlag(FLAGS_seed);
  if (Given("generators")) scvd.generator_count = absl::GetFlag(FLAGS_generators);
  if (Given("thickness")) scvd.mean_thickness_voxels = absl::GetFlag(FLAGS_thickness);
  if (Given("lloyd_max_iter")) scvd.lloyd_max_iter = absl::GetFlag(FLAGS_lloyd_max_iter);
  if (Given("lloyd_tol")) scvd.lloyd_tol = absl::GetFlag(FLAGS_lloyd_tol);
  if (Given("fold_angle")) o.surface.triangles.fold_angle_degrees = absl::GetFlag(FLAGS_fold_angle);
  const std::string placement = absl::GetFlag(FLAGS_placement);
  if (placement == "generator") {
    o.surface.placement = VertexPlacement::kGenerator;
  } else if (placement == "centroid") {
    o.surface.placement = VertexPlacement::kCentroid;
  } else if (!placement.empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat("--placement=", placement, " is not known; use generator or centroid"));
  }
  const std::string measure = absl::GetFlag(FLAGS_thickness_measure);
  if (measure == "axis_runs") {
    o.surface.thickness = ThicknessMeasure::kAxisRuns;
  } else if (measure == "normal") {
    o.surface.thickness = ThicknessMeasure::kNormal;
  } else if (!measure.empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat("--thickness_measure=", measure, " is not known; use axis_runs or normal"));
  }
  const std::string rim = absl::GetFlag(FLAGS_rim);
  if (rim == "true" || rim == "false") {
    o.surface.triangles.rim = rim == "true";
  } else if (!rim.empty()) {
    return absl::InvalidArgumentError(absl::StrCat("--rim=", rim, " must be true or false"));
  }
  if (Given("similarity_model")) {
    const std::string model = absl::GetFlag(FLAGS_similarity_model);
    if (model != "vertex" && model != "face") {
      return absl::InvalidArgumentError(
          absl::StrCat("--similarity_model=", model, " is not known; use face or vertex"));
    }
    o.score.height = model == "vertex" ? PrismHeight::kVertex : PrismHeight::kFace;
    o.radius_search.height = o.score.height;
  }
  if (Given("target_similarity")) {
    o.search_radius = true;
    o.radius_search.goal = RadiusGoal::kTargetSimilarity;
    o.radius_search.target_similarity = absl::GetFlag(FLAGS_target_similarity);
  } else if (absl::GetFlag(FLAGS_search_best)) {
    o.search_radius = true;
    o.radius_search.goal = RadiusGoal::kBestSimilarity;
  }
  if (Given("r_min")) o.radius_search.min_radius_voxels = absl::GetFlag(FLAGS_r_min);
  if (Given("r_max")) o.radius_search.max_radius_voxels = absl::GetFlag(FLAGS_r_max);
  if (Given("hausdorff")) o.score.hausdorff = absl::GetFlag(FLAGS_hausdorff);
  if (Given("grid_rates")) {
    o.score.grid_rates.clear();
    for (absl::string_view k :
         absl::StrSplit(absl::GetFlag(FLAGS_grid_rates), ',', absl::SkipEmpty())) {
      int rate = 0;
      if (!absl::SimpleAtoi(k, &rate) || rate < 1) {
        return absl::InvalidArgumentError(
            absl::StrCat("--grid_rates: '", k, "' is not an integer >= 1"));
      }
      o.score.grid_rates.push_back(rate);
    }
  }
  if (Given("formats")) {
    o.output.ply = o.output.vtp = o.output.obj = false;
    for (absl::string_view f :
         absl::StrSplit(absl::GetFlag(FLAGS_formats), ',', absl::SkipEmpty())) {
      if (f == "ply") {
        o.output.ply = true;
      } else if (f == "vtp") {
        o.output.vtp = true;
      } else if (f == "obj") {
        o.output.obj = true;
      } else {
        return absl::InvalidArgumentError(
            absl::StrCat("--formats: '", f, "' is not ply, vtp or obj"));
      }
    }
  }
  ExtractionOptions& x = o.extraction;
  if (Given("refine")) x.refine = absl::GetFlag(FLAGS_refine);
  if (Given("refine_close")) x.refine_close_radius = absl::GetFlag(FLAGS_refine_close);
  if (Given("refine_open")) x.refine_open_radius = absl::GetFlag(FLAGS_refine_open);
  if (Given("detect")) x.detect = absl::GetFlag(FLAGS_detect);
  if (Given("detect_t")) x.detect_extend.half_thickness_voxels = absl::GetFlag(FLAGS_detect_t);
  if (Given("detect_R")) x.detect_extend.radius_voxels = absl::GetFlag(FLAGS_detect_R);
  if (Given("detect_rounds")) x.detect_extend.max_rounds = absl::GetFlag(FLAGS_detect_rounds);
  if (Given("M")) x.min_object_voxels = absl::GetFlag(FLAGS_M);
  if (Given("separate")) x.separate = absl::GetFlag(FLAGS_separate);
  if (Given("r_sep")) {
    x.separation.radius_voxels = absl::GetFlag(FLAGS_r_sep);
    x.detect_extend.scvd_radius_voxels = x.recover_extend.scvd_radius_voxels =
        x.separation.radius_voxels;
  }
  if (Given("D_ang")) x.separation.dihedral_degrees = absl::GetFlag(FLAGS_D_ang);
  if (Given("remove_minor")) x.remove_minor = absl::GetFlag(FLAGS_remove_minor);
  if (Given("recover")) x.recover = absl::GetFlag(FLAGS_recover);
  if (Given("recover_t")) x.recover_extend.half_thickness_voxels = absl::GetFlag(FLAGS_recover_t);
  if (Given("recover_R")) x.recover_extend.radius_voxels = absl::GetFlag(FLAGS_recover_R);
  if (Given("recover_rounds")) x.recover_extend.max_rounds = absl::GetFlag(FLAGS_recover_rounds);
  SM_RETURN_IF_ERROR(VolumeFromFlags(&o));
  if (Given("volume_mesh")) o.volume_mesh = absl::GetFlag(FLAGS_volume_mesh);
  o.output.dir = absl::GetFlag(FLAGS_o);
  if (o.output.dir.empty()) return absl::InvalidArgumentError("needs -o DIR");
  SM_RETURN_IF_ERROR(ValidatePipelineOptions(o));
  return o;
}

absl::Status Surface(const std::vector<std::string>& args, bool extract) {
  if (args.size() != 1) {
    return absl::InvalidArgumentError(
        absl::StrCat("usage: ", extract ? "run" : "surface", " VOLUME -o DIR [flags]"));
  }
  SM_ASSIGN_OR_RETURN(PipelineOptions o, PipelineFromFlags(args[0], extract));
  return RunSurface(o, std::cout);
}

// `volume SURFACE.ply (--volume VOL | --box NXxNYxNZ) -o DIR`: the volume mesh of a
// surface file already made.
absl::Status Volume(const std::vector<std::string>& args) {
  if (args.size() != 1)
    return absl::InvalidArgumentError(
        "usage: volume SURFACE.ply (--volume VOL | --box NXxNYxNZ) -o DIR");
  PipelineOptions o;
  if (!absl::GetFlag(FLAGS_config).empty()) {
    SM_ASSIGN_OR_RETURN(std::string text, ReadFileToString(absl::GetFlag(FLAGS_config)));
    SM_RETURN_IF_ERROR(ApplyPipelineConfig(text, absl::GetFlag(FLAGS_config), &o));
  }
  SM_RETURN_IF_ERROR(VolumeFromFlags(&o));
  SM_RETURN_IF_ERROR(ValidatePipelineOptions(o));
  VolumeInfo box;
  if (!absl::GetFlag(FLAGS_volume).empty()) {
    SM_ASSIGN_OR_RETURN(SheetInput in, InputFromFlags(absl::GetFlag(FLAGS_volume)));
    SM_ASSIGN_OR_RETURN(auto source, OpenVolume(in.path, in.open));
    box = source->info();
  } else if (!absl::GetFlag(FLAGS_box).empty()) {
    SM_ASSIGN_OR_RETURN(box.dims, ParseDims("box", absl::GetFlag(FLAGS_box)));
    SM_ASSIGN_OR_RETURN(SheetInput in, InputFromFlags(""));
    if (in.open.spacing) box.placement.spacing = *in.open.spacing;
    if (in.open.origin) box.placement.origin = *in.open.origin;
  } else {
    return absl::InvalidArgumentError("volume needs the box: --volume VOL or --box NXxNYxNZ");
  }
  o.output.dir = absl::GetFlag(FLAGS_o);
  if (o.output.dir.empty()) return absl::InvalidArgumentError("volume needs -o DIR");
  return RunVolume(args[0], box, o, std::cout);
}

absl::Status Score(const std::vector<std::string>& args) {
  if (args.size() != 2)
    return absl::InvalidArgumentError("usage: score VOLUME MESH [--closed] [--json]");
  ScoreCommandOptions o;
  SM_ASSIGN_OR_RETURN(o.input, InputFromFlags(args[0]));
  o.mesh_path = args[1];
  o.closed = absl::GetFlag(FLAGS_closed);
  o.hausdorff = absl::GetFlag(FLAGS_hausdorff);
  o.json = absl::GetFlag(FLAGS_json);
  return RunScore(o, std::cout);
}

// absl flags take underscores; accept --target-similarity as well as --target_similarity.
// Records which flags were given.
void NormalizeFlagNames(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    char* a = argv[i];
    if (a[0] != '-') continue;
    char* name = a + (a[1] == '-' ? 2 : 1);
    char* c = name;
    for (; *c != '\0' && *c != '='; ++c) {
      if (*c == '-' && a[1] == '-') *c = '_';
    }
    std::string flag(name, c);
    if (flag.rfind("no", 0) == 0 && absl::FindCommandLineFlag(flag) == nullptr)
      flag = flag.substr(2);
    GivenFlags().insert(flag);
  }
}

int Main(int argc, char** argv) {
  NormalizeFlagNames(argc, argv);
  absl::SetProgramUsageMessage(kUsage);
  std::vector<char*> rest = absl::ParseCommandLine(argc, argv);
  if (rest.size() < 2) {
    std::cerr << kUsage << "\n";
    return 2;
  }
  const std::string command = rest[1];
  const std::vector<std::string> args(rest.begin() + 2, rest.end());
  absl::Status status;
  if (command == "info") {
    status = Info(args);
  } else if (command == "phantom") {
    status = Phantom(args);
  } else if (command == "convert") {
    status = Convert(args);
  } else if (command == "surface") {
    status = Surface(args, /*extract=*/false);
  } else if (command == "run") {
    status = Surface(args, /*extract=*/true);
  } else if (command == "volume") {
    status = Volume(args);
  } else if (command == "score") {
    status = Score(args);
  } else {
    std::cerr << "unknown command '" << command << "'\n\n" << kUsage << "\n";
    return 2;
  }
  if (!status.ok()) {
    std::cerr << "sheetmesh-pipeline " << command << ": " << absl::StatusCodeToString(status.code())
              << ": " << status.message() << "\n";
    return status.code() == absl::StatusCode::kInvalidArgument ? 2 : 1;
  }
  return 0;
}

}  // namespace
}  // namespace sheetmesh

int main(int argc, char** argv) {
  sheetmesh::UseTransparentHugePages(argc, argv);
  return sheetmesh::Main(argc, argv);
}
