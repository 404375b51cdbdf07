#include "worker/pipeline/cli/phantom_command.h"

#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "common/file_util.h"
#include "common/status_macros.h"

namespace sheetmesh {
namespace {

// A raw file says neither its dims nor its type: where its name does not either, how to read
// it back ("" where it does).
std::string RawReadBackHint(const std::string& path, VolumeFormat format, const VolumeInfo& info) {
  if (format != VolumeFormat::kRaw) return "";
  const auto named = DimsFromFileName(path);
  if (named.ok() && *named && (*named)->first == info.dims && (*named)->second == info.dtype) {
    return "";
  }
  return absl::StrFormat(
      "a raw file holds no dims: read it back with --dims=%s --dtype=%s, or name it like "
      "rock_%s_%s.raw\n",
      info.dims.ToString(), DTypeName(info.dtype), info.dims.ToString(),
      info.dtype == DType::kUInt8    ? "u8"
      : info.dtype == DType::kUInt16 ? "u16"
                                     : "f32");
}

}  // namespace

absl::Status RunPhantom(const PhantomCommandOptions& options, std::ostream& out) {
  const absl::Time start = absl::Now();
  SM_ASSIGN_OR_RETURN(PhantomTruth truth, PlanPhantom(options.phantom));
  VolumeInfo info;
  info.dims = options.phantom.dims;
  info.dtype = options.phantom.dtype;
  SM_ASSIGN_OR_RETURN(auto sink, CreateVolumeWriter(options.output, info, options.format));
  SM_RETURN_IF_ERROR(GeneratePhantom(&truth, *sink));
  const std::string truth_path =
      options.truth_path.empty() ? options.output + ".truth.json" : options.truth_path;
  SM_RETURN_IF_ERROR(WriteFileAtomically(truth_path, truth.ToJson()));
  out << absl::StrFormat(
      "wrote %s (%s %s, %d sheets, %d specks, %d sheet voxels = %.2f%%) and %s in %.1f s\n",
      options.output, options.phantom.dims.ToString(), DTypeName(options.phantom.dtype),
      truth.sheets.size(), truth.specks.size(), truth.sheet_voxels,
      100.0 * truth.sheet_voxels / options.phantom.dims.num_voxels(), truth_path,
      absl::ToDoubleSeconds(absl::Now() - start));
  out << RawReadBackHint(options.output, options.format, info);
  return absl::OkStatus();
}

absl::Status RunConvert(const std::string& input, const OpenOptions& open,
                        const std::string& output, VolumeFormat format, std::ostream& out) {
  SM_ASSIGN_OR_RETURN(auto source, OpenVolume(input, open));
  const VolumeInfo& info = source->info();
  SM_ASSIGN_OR_RETURN(auto sink, CreateVolumeWriter(output, info, format));
  const int64_t slice = info.dims.nx * info.dims.ny * BytesPerVoxel(info.dtype);
  const int64_t slab = std::max<int64_t>(1, (int64_t{32} << 20) / slice);
  std::vector<std::byte> buffer(static_cast<size_t>(std::min(slab, info.dims.nz) * slice));
  for (int64_t z = 0; z < info.dims.nz; z += slab) {
    const int64_t n = std::min(slab, info.dims.nz - z);
    std::span<std::byte> part(buffer.data(), static_cast<size_t>(n * slice));
    SM_RETURN_IF_ERROR(source->ReadSlices(z, n, part));
    SM_RETURN_IF_ERROR(sink->WriteSlices(n, part));
  }
  SM_RETURN_IF_ERROR(sink->Finish());
  out << absl::StrFormat("wrote %s (%s %s)\n", output, info.dims.ToString(), DTypeName(info.dtype));
  out << RawReadBackHint(output, format, info);
  return absl::OkStatus();
}

}  // namespace sheetmesh
