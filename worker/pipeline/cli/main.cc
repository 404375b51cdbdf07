// sheetmesh-pipeline: the offline pipeline, no server needed. COMMAND comes first:
//   sheetmesh-pipeline info|surface|run|volume|score|phantom|convert|params ARGS [FLAGS]
// Pipeline parameters are flags named after the parameter table (parameter_flags.h); the
// flags below are the commands' own.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <iostream>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "common/exit_codes.h"
#include "common/file_util.h"
#include "common/flags_help.h"
#include "common/huge_pages.h"
#include "common/machine.h"
#include "common/status_macros.h"
#include "worker/pipeline/brick/bricks.h"
#include "worker/pipeline/cli/info_command.h"
#include "worker/pipeline/cli/parameter_flags.h"
#include "worker/pipeline/cli/phantom_command.h"
#include "worker/pipeline/cli/surface_command.h"
#include "worker/pipeline/phantom/phantom_presets.h"
#include "worker/pipeline/volume/child_reader.h"

ABSL_FLAG(double, memory_limit_gb, -1,
          "the address space this program may use, in GiB (default: three quarters of the "
          "machine's memory; 0: no limit); past it a reader or stage fails cleanly instead of "
          "the kernel's out-of-memory killer ending the program");
ABSL_FLAG(std::string, o, "", "output path (a folder; phantom and convert: the volume file)");
ABSL_FLAG(std::string, config, "",
          "surface/run/volume: a JSON file of parameters (flags given override it)");
ABSL_FLAG(bool, isolate_readers, true,
          "read a file whose format a third-party library parses (vdb, hdf5, dicom, png, jpeg, "
          "tiff, folders of slices) in a child process with a memory limit, so that a damaged "
          "file costs that child");
ABSL_FLAG(bool, json, false, "info, score, params: print JSON");
ABSL_FLAG(int, connectivity, 6, "info: component connectivity, 6, 18 or 26");
ABSL_FLAG(int, largest, 10, "info: component sizes to list");
ABSL_FLAG(bool, closed, false, "score: the mesh is a closed surface; score the volume it encloses");
ABSL_FLAG(std::string, box, "", "volume: the box NXxNYxNZ in voxels, when no --volume is given");
ABSL_FLAG(std::string, volume, "",
          "volume: the image whose box, spacing and origin the mesh fills");
ABSL_FLAG(
    std::string, out_format, "",
    "phantom and convert: raw, tiff, tiff-folder, nrrd, nrrd-gzip, vdb or hdf5 (default: by the "
    "output's extension, raw when it names none of them)");
ABSL_FLAG(bool, markdown, false, "params: print the markdown table of docs/parameters.md");
// phantom
ABSL_FLAG(std::string, preset, "",
          "phantom: sample (the demo volume), paper (1012x1024x931), thick_slab, rough_network, "
          "rough_slab, shallow_network, grazing_sheet or vuggy_network");
ABSL_FLAG(std::string, dims, "", "phantom: its size NXxNYxNZ");
ABSL_FLAG(std::string, phantom_dims, "", "phantom: its size NXxNYxNZ (as --dims)");
ABSL_FLAG(std::string, dtype, "", "phantom: voxel type uint8, uint16 or float32");
ABSL_FLAG(uint64_t, seed, 1, "phantom: random seed");
ABSL_FLAG(double, junction_degrees, -1,
          "phantom: two sheets meeting at this angle, 1-90 (default: the preset's; 0: none)");
ABSL_FLAG(std::string, junction, "", "phantom: x (the sheets cross) or t (one ends on the other)");
ABSL_FLAG(int, sheets, -1, "phantom: sheets (default: the preset's)");
ABSL_FLAG(double, aperture, -1, "phantom: mean aperture in voxels (default: the preset's)");
ABSL_FLAG(int, specks, -2, "phantom: specks (-1: one per 20^3 voxels; default: the preset's)");
// plan, brick
ABSL_FLAG(std::string, brick_size, "auto",
          "plan: the bricks' edge in voxels, N or NXxNYxNZ (the last bricks along an axis are "
          "what is left; 0 along an axis: chosen); auto: slabs of whole slices, about 128 M "
          "voxels each, which read every byte of a file once");
ABSL_FLAG(std::string, grid_origin, "0,0,0",
          "plan: where the brick grid starts, X,Y,Z voxels (each in [0, the brick size))");
ABSL_FLAG(int, index, -1,
          "brick: the brick to run (default: $SLURM_ARRAY_TASK_ID, or a Kubernetes indexed "
          "Job's $JOB_COMPLETION_INDEX)");
ABSL_FLAG(std::string, truth, "", "phantom: ground truth JSON (default: OUTPUT.truth.json)");

namespace sheetmesh {
namespace {

constexpr char kUsage[] =
    "sheetmesh-pipeline COMMAND [ARGS] [FLAGS]\n\n"
    "commands:\n"
    "  info VOLUME             dims, sheet voxels, thickness and components of a volume\n"
    "  surface VOLUME -o DIR   mesh every sheet voxel as it is (run with --extract=false): --r R,\n"
    "                          or --target_similarity S, or --search_best\n"
    "  run VOLUME -o DIR       extract the major sheets (Fig. 3), then mesh and score them (the\n"
    "                          service's jobs run this);\n"
    "                          --volume_mesh adds the TetGen volume mesh\n"
    "  volume SURFACE.ply -o DIR  tetrahedralize the box (--volume VOL or --box) around a surface\n"
    "  score VOLUME MESH       score a .ply/.obj against the volume (--closed for closed "
    "surfaces)\n"
    "  phantom -o FILE         write a synthetic rock volume and its ground truth\n"
    "  convert VOLUME -o FILE  copy a volume into --out_format (raw, tiff, nrrd, vdb, ...)\n"
    "  plan VOLUME -o PLAN     cut the volume into bricks (--brick_size) for a job's flags;\n"
    "  brick PLAN --index=I    each brick read and selected by its own process (a Slurm array\n"
    "  merge PLAN -o DIR       task); the merge joins them and runs the job (deploy/slurm/)\n"
    "  params                  the parameter table (--markdown, --json)\n\n"
    "Every parameter is a flag named after its key (--separate_r=6 or --separate.r 6) and a key\n"
    "of a --config JSON file ({\"separate\": {\"r\": 6}}); flags override the file. Flags may\n"
    "be written with dashes or underscores.";

bool IsInput(const ParamSpec& s) { return absl::StartsWith(s.key, "input."); }

// The parameters each command uses.
std::function<bool(const ParamSpec&)> Accepts(const std::string& command) {
  if (command == "surface" || command == "run" || command == "plan") {
    return [](const ParamSpec&) { return true; };
  }
  if (command == "volume") {
    return [](const ParamSpec& s) {
      return IsInput(s) || absl::StartsWith(s.key, "tet.") || absl::StartsWith(s.key, "plc.") ||
             absl::StartsWith(s.key, "improve.") || s.key == "max_tetrahedra" ||
             s.key == "output.volume_formats";
    };
  }
  if (command == "score") {
    return [](const ParamSpec& s) { return IsInput(s) || s.key == "similarity.hausdorff"; };
  }
  if (command == "info" || command == "convert") return IsInput;
  return [](const ParamSpec&) { return false; };
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

// Defaults, then --config, then the parameter flags given.
// The surface command is run without the extraction; every other command takes the table's
// defaults, as the service does.
// The child readers' program: this one (its `_serve-volume` command), unless
// --isolate_readers=false or the system does not say where it is.
ChildReaderOptions ChildReaders() {
  ChildReaderOptions o;
  if (!absl::GetFlag(FLAGS_isolate_readers)) return o;
  char path[4096];
  const ssize_t n = ::readlink("/proc/self/exe", path, sizeof(path) - 1);
  if (n > 0) o.program.assign(path, static_cast<size_t>(n));
  return o;
}

absl::StatusOr<PipelineOptions> Options(const ParameterFlags& flags, bool surface_command) {
  ParameterBuilder builder;
  PipelineOptions base;
  if (surface_command) base.extract = false;
  if (!absl::GetFlag(FLAGS_config).empty()) {
    SM_ASSIGN_OR_RETURN(std::string text, ReadFileToString(absl::GetFlag(FLAGS_config)));
    SM_RETURN_IF_ERROR(builder.AddJson(text, absl::GetFlag(FLAGS_config)));
  }
  SM_ASSIGN_OR_RETURN(PipelineOptions o, builder.Build(base));
  SM_ASSIGN_OR_RETURN(o, flags.given.Build(o));
  o.input.open.child_reader = ChildReaders();
  return o;
}

absl::Status Usage(absl::string_view what) {
  return absl::InvalidArgumentError(absl::StrCat("usage: sheetmesh-pipeline ", what));
}

absl::Status Info(const std::vector<std::string>& args, const PipelineOptions& o) {
  if (args.size() != 1) return Usage("info VOLUME [flags]");
  InfoOptions options;
  options.input = o.input;
  options.input.path = args[0];
  SM_ASSIGN_OR_RETURN(options.connectivity, ParseConnectivity(absl::GetFlag(FLAGS_connectivity)));
  options.largest_components = absl::GetFlag(FLAGS_largest);
  options.json = absl::GetFlag(FLAGS_json);
  return RunInfo(options, std::cout);
}

absl::Status Phantom(const std::vector<std::string>& args) {
  if (!args.empty()) return Usage("phantom -o FILE [flags]");
  PhantomCommandOptions options;
  const std::string preset = absl::GetFlag(FLAGS_preset);
  if (!preset.empty()) {
    SM_ASSIGN_OR_RETURN(options.phantom, PhantomPreset(preset));
  }
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
  if (absl::GetFlag(FLAGS_junction_degrees) >= 0) {
    options.phantom.junction_degrees = absl::GetFlag(FLAGS_junction_degrees);
  }
  const std::string junction = absl::GetFlag(FLAGS_junction);
  if (!junction.empty()) {
    if (junction != "x" && junction != "t") {
      return absl::InvalidArgumentError(
          absl::StrCat("--junction=", junction, ": give x (the sheets cross) or t"));
    }
    options.phantom.junction_t = junction == "t";
  }
  options.output = absl::GetFlag(FLAGS_o);
  if (options.output.empty()) return absl::InvalidArgumentError("phantom needs -o FILE");
  SM_ASSIGN_OR_RETURN(options.format,
                      OutputVolumeFormat(absl::GetFlag(FLAGS_out_format), options.output));
  options.truth_path = absl::GetFlag(FLAGS_truth);
  return RunPhantom(options, std::cout);
}

absl::Status Convert(const std::vector<std::string>& args, const PipelineOptions& o) {
  if (args.size() != 1) return Usage("convert VOLUME -o FILE --out_format=F");
  SM_ASSIGN_OR_RETURN(VolumeFormat format,
                      OutputVolumeFormat(absl::GetFlag(FLAGS_out_format), absl::GetFlag(FLAGS_o)));
  if (absl::GetFlag(FLAGS_o).empty()) return absl::InvalidArgumentError("convert needs -o FILE");
  return RunConvert(args[0], o.input.open, absl::GetFlag(FLAGS_o), format, std::cout);
}

absl::Status Plan(const std::vector<std::string>& args, PipelineOptions o) {
  if (args.size() != 1) return Usage("plan VOLUME -o PLAN_DIR [--brick_size=N] [job flags]");
  const std::string dir = absl::GetFlag(FLAGS_o);
  if (dir.empty()) return absl::InvalidArgumentError("plan needs -o PLAN_DIR");
  o.input.path = args[0];
  BrickGrid grid;
  SM_ASSIGN_OR_RETURN(grid.size, ParseBrickSize(absl::GetFlag(FLAGS_brick_size), "--brick_size"));
  const std::vector<std::string> origin = absl::StrSplit(absl::GetFlag(FLAGS_grid_origin), ',');
  if (origin.size() != 3 || !absl::SimpleAtoi(origin[0], &grid.origin.x) ||
      !absl::SimpleAtoi(origin[1], &grid.origin.y) ||
      !absl::SimpleAtoi(origin[2], &grid.origin.z)) {
    return absl::InvalidArgumentError(
        absl::StrCat("--grid_origin=", absl::GetFlag(FLAGS_grid_origin), " must look like 0,0,0"));
  }
  SM_ASSIGN_OR_RETURN(const BrickPlan plan, MakeBrickPlan(o, grid));
  SM_RETURN_IF_ERROR(WriteBrickPlan(plan, dir));
  const Index3& size = plan.grid.size;
  std::cout << "plan        " << plan.bricks.size() << " bricks of up to " << size.x << "x"
            << size.y << "x" << size.z << " over " << plan.info.dims.ToString() << " (halo "
            << plan.halo << "; in bricks: " << absl::StrJoin(plan.in_bricks, ", ") << ")\n"
            << "next        sheetmesh-pipeline brick " << dir << " --index=I   (I = 0 .. "
            << plan.bricks.size() - 1 << "), then: sheetmesh-pipeline merge " << dir << " -o OUT\n";
  return absl::OkStatus();
}

// --index, or the array task's index the scheduler gives.
absl::StatusOr<int> BrickIndex() {
  if (absl::GetFlag(FLAGS_index) >= 0) return absl::GetFlag(FLAGS_index);
  for (const char* name : {"SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"}) {
    const char* v = std::getenv(name);
    int index = 0;
    if (v == nullptr) continue;
    if (!absl::SimpleAtoi(v, &index) || index < 0) {
      return absl::InvalidArgumentError(
          absl::StrCat("$", name, " = \"", v, "\" is not a brick index"));
    }
    return index;
  }
  return absl::InvalidArgumentError(
      "brick needs its index: --index=I, or run it as a Slurm array task ($SLURM_ARRAY_TASK_ID) "
      "or a Kubernetes indexed Job ($JOB_COMPLETION_INDEX)");
}

absl::Status BrickCommand(const std::vector<std::string>& args) {
  if (args.size() != 1) return Usage("brick PLAN_DIR --index=I");
  SM_ASSIGN_OR_RETURN(const int index, BrickIndex());
  const absl::Time start = absl::Now();
  SM_ASSIGN_OR_RETURN(const BrickResult r,
                      RunBrick(args[0], index, {}, {.child_reader = ChildReaders()}));
  std::cout << absl::StrFormat("brick       %d (%s): %d sheet voxels, %d bytes in %s, %.2f s\n",
                               index, r.core.ToString(), r.sheet.size(), r.file_bytes,
                               BrickFile(args[0], index),
                               absl::ToDoubleSeconds(absl::Now() - start));
  return absl::OkStatus();
}

absl::Status Merge(const std::vector<std::string>& args) {
  if (args.size() != 1) return Usage("merge PLAN_DIR -o DIR");
  const std::string dir = absl::GetFlag(FLAGS_o);
  if (dir.empty()) return absl::InvalidArgumentError("merge needs -o DIR");
  return RunMergeCommand(args[0], dir, std::cout);
}

absl::Status Surface(const std::vector<std::string>& args, const std::string& command,
                     PipelineOptions o) {
  if (args.size() != 1) return Usage(absl::StrCat(command, " VOLUME -o DIR [flags]"));
  o.input.path = args[0];
  o.output.dir = absl::GetFlag(FLAGS_o);
  if (o.output.dir.empty()) return absl::InvalidArgumentError(command + " needs -o DIR");
  return RunSurface(o, std::cout);
}

// `volume SURFACE.ply (--volume VOL | --box NXxNYxNZ) -o DIR`: the volume mesh of a
// surface file already made.
absl::Status Volume(const std::vector<std::string>& args, PipelineOptions o) {
  if (args.size() != 1) return Usage("volume SURFACE.ply (--volume VOL | --box NXxNYxNZ) -o DIR");
  VolumeInfo box;
  if (!absl::GetFlag(FLAGS_volume).empty()) {
    SM_ASSIGN_OR_RETURN(auto source, OpenVolume(absl::GetFlag(FLAGS_volume), o.input.open));
    box = source->info();
  } else if (!absl::GetFlag(FLAGS_box).empty()) {
    SM_ASSIGN_OR_RETURN(box.dims, ParseDims("box", absl::GetFlag(FLAGS_box)));
    if (o.input.open.spacing) box.placement.spacing = *o.input.open.spacing;
    if (o.input.open.origin) box.placement.origin = *o.input.open.origin;
  } else {
    return absl::InvalidArgumentError("volume needs the box: --volume VOL or --box NXxNYxNZ");
  }
  o.output.dir = absl::GetFlag(FLAGS_o);
  if (o.output.dir.empty()) return absl::InvalidArgumentError("volume needs -o DIR");
  return RunVolume(args[0], box, o, std::cout);
}

absl::Status Score(const std::vector<std::string>& args, const PipelineOptions& o) {
  if (args.size() != 2) return Usage("score VOLUME MESH [--closed] [--json]");
  ScoreCommandOptions options;
  options.input = o.input;
  options.input.path = args[0];
  options.mesh_path = args[1];
  options.closed = absl::GetFlag(FLAGS_closed);
  options.hausdorff = o.score.hausdorff;
  options.json = absl::GetFlag(FLAGS_json);
  return RunScore(options, std::cout);
}

absl::Status Params() {
  if (absl::GetFlag(FLAGS_markdown)) {
    std::cout << ParametersMarkdown();
  } else if (absl::GetFlag(FLAGS_json)) {
    std::cout << CanonicalParametersJson(PipelineOptions(), /*include_local=*/true) << "\n";
  } else {
    std::cout << ParameterFlagsHelp([](const ParamSpec&) { return true; });
  }
  return absl::OkStatus();
}

absl::Status Dispatch(const std::string& command, const std::vector<std::string>& args,
                      const ParameterFlags& flags) {
  if (command == "phantom") return Phantom(args);
  if (command == "params") return Params();
  if (command == "brick") return BrickCommand(args);
  if (command == "merge") return Merge(args);
  SM_ASSIGN_OR_RETURN(PipelineOptions o, Options(flags, /*surface_command=*/command == "surface"));
  if (command == "info") return Info(args, o);
  if (command == "convert") return Convert(args, o);
  if (command == "surface" || command == "run") return Surface(args, command, o);
  if (command == "volume") return Volume(args, o);
  if (command == "plan") return Plan(args, o);
  if (command == "score") return Score(args, o);
  return absl::InvalidArgumentError(
      absl::StrCat("unknown command '", command, "'; sheetmesh-pipeline --help lists them"));
}

// --help: the usage, the parameters the command takes, and the commands' own flags.
void PrintHelp(const std::string& command) {
  std::cout << kUsage << "\n\n";
  const std::function<bool(const ParamSpec&)> accepts =
      command.empty() ? [](const ParamSpec&) { return true; } : Accepts(command);
  const std::string params = ParameterFlagsHelp(accepts);
  if (!params.empty()) {
    std::cout << "Parameters" << (command.empty() ? "" : " of '" + command + "'") << ":\n"
              << params << "\n";
  }
  std::cout << "Other flags:\n";
  PrintFlagsOf("cli/main.cc", std::cout);
}

// A header may claim any size, and a third-party reader (OpenVDB) believes it: with a limit
// on the address space that claim is std::bad_alloc, reported as a bad file.
absl::Status LimitMemory(double gib) {
  if (gib == 0) return absl::OkStatus();
  if (gib < 0 && gib != -1) {
    return absl::InvalidArgumentError(
        absl::StrCat("--memory_limit_gb=", gib, ": give a size in GiB, or 0 for no limit"));
  }
  const uint64_t bytes = gib < 0 ? PhysicalMemoryBytes(0) / 4 * 3
                                 : static_cast<uint64_t>(gib * double(uint64_t{1} << 30));
  if (bytes == 0) return absl::OkStatus();  // the system did not say
  struct rlimit rl;
  if (::getrlimit(RLIMIT_AS, &rl) != 0) return absl::OkStatus();
  if (rl.rlim_cur != RLIM_INFINITY && rl.rlim_cur <= bytes) return absl::OkStatus();
  rl.rlim_cur = bytes;
  ::setrlimit(RLIMIT_AS, &rl);  // refused only above the hard limit, which then holds
  return absl::OkStatus();
}

// `_serve-volume SPEC`: opens the spec's volume here and serves it to the parent.
int ServeVolumeCommand(const std::string& text) {
  absl::StatusOr<ChildReaderSpec> spec = ParseChildReaderSpec(text);
  if (!spec.ok()) return ServeVolume(spec.status()).ok() ? 0 : 1;
  OpenOptions open;
  open.format = spec->format;
  open.vdb_grid = spec->vdb_grid;
  open.limits = spec->limits;
  return ServeVolume(OpenVolume(spec->path, open)).ok() ? 0 : 1;
}

int Main(int argc, char** argv) {
  absl::SetProgramUsageMessage(kUsage);
  // A child reader (child_reader.h), started by this program itself: not a user's command.
  if (argc == 3 && std::string(argv[1]) == "_serve-volume") return ServeVolumeCommand(argv[2]);
  const std::string command = argc > 1 && argv[1][0] != '-' ? argv[1] : "";
  if (WantsVersion(argc, argv)) {
    PrintVersion("sheetmesh-pipeline", std::cout);
    return 0;
  }
  if (WantsHelp(argc, argv)) {
    PrintHelp(command);
    return 0;
  }
  if (command.empty()) {
    std::cerr << kUsage << "\n";
    return 2;
  }
  // phantom and params take no pipeline parameters: their flags are all their own.
  absl::StatusOr<ParameterFlags> flags =
      command == "phantom" || command == "params" || command == "brick" || command == "merge"
          ? ParameterFlags{std::vector<char*>(argv, argv + argc), {}, {}}
          : TakeParameterFlags(argc, argv, Accepts(command), command);
  absl::Status status = flags.status();
  if (status.ok()) {
    std::vector<char*> positional = sheetmesh::ParseFlagsOrExit(
        static_cast<int>(flags->rest.size()), flags->rest.data(), "sheetmesh-pipeline");
    const std::vector<std::string> args(positional.begin() + std::min<size_t>(2, positional.size()),
                                        positional.end());
    status = LimitMemory(absl::GetFlag(FLAGS_memory_limit_gb));
    if (status.ok()) status = Dispatch(command, args, *flags);
  }
  if (!status.ok()) {
    std::cerr << "sheetmesh-pipeline " << command << ": " << absl::StatusCodeToString(status.code())
              << ": " << status.message() << "\n";
    return ExitCodeOf(status, /*about_user_input=*/true);  // its files are the user's
  }
  return 0;
}

}  // namespace
}  // namespace sheetmesh

int main(int argc, char** argv) {
  sheetmesh::UseTransparentHugePages(argc, argv);
  return sheetmesh::Main(argc, argv);
}
