// sheetmesh-pipeline: the offline pipeline, no server needed.
//   sheetmesh-pipeline info VOLUME [selection flags] [--json]
//   sheetmesh-pipeline phantom -o FILE [--preset sample|paper] [phantom flags]
#include <iostream>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "worker/pipeline/cli/info_command.h"
#include "worker/pipeline/cli/phantom_command.h"
#include "worker/pipeline/core/huge_pages.h"
#include "worker/pipeline/core/status_macros.h"

// Volume input.
ABSL_FLAG(std::string, format, "", "volume format: raw, tiff, nrrd, vdb (default: by extension)");
ABSL_FLAG(std::string, dims, "", "raw volumes: NXxNYxNZ (default: from a name like a_64x64x32_u8.raw)");
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
// phantom
ABSL_FLAG(std::string, o, "", "output path");
ABSL_FLAG(std::string, out_format, "raw", "phantom output: raw, tiff, tiff-folder, nrrd, nrrd-gzip, vdb");
ABSL_FLAG(std::string, preset, "", "phantom preset: sample (the demo volume) or paper (1012x1024x931)");
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
    "  info VOLUME        dims, sheet voxels, thickness and components of a volume\n"
    "  phantom -o FILE    write a synthetic rock volume and its ground truth\n\n"
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
    SM_ASSIGN_OR_RETURN(in.selection,
                        ParsePhaseSelection("labels=" + absl::GetFlag(FLAGS_labels)));
  } else if (!absl::GetFlag(FLAGS_window).empty()) {
    SM_ASSIGN_OR_RETURN(in.selection,
                        ParsePhaseSelection("window=" + absl::GetFlag(FLAGS_window)));
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
  if (!absl::GetFlag(FLAGS_phantom_dims).empty()) {
    SM_ASSIGN_OR_RETURN(options.phantom.dims,
                        ParseDims("phantom_dims", absl::GetFlag(FLAGS_phantom_dims)));
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

int Main(int argc, char** argv) {
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
  } else {
    std::cerr << "unknown command '" << command << "'\n\n" << kUsage << "\n";
    return 2;
  }
  if (!status.ok()) {
    std::cerr << "sheetmesh-pipeline " << command << ": "
              << absl::StatusCodeToString(status.code()) << ": " << status.message() << "\n";
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
