#include "worker/runtime/job_parameters.h"

#include <cstdint>
#include <optional>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "worker/pipeline/brick/bricks.h"
#include "worker/pipeline/run/parameters.h"

namespace sheetmesh::runtime {
namespace {

namespace pb = ::google::protobuf;

// A set field's value; nullopt when unset (no presence bit, an empty string or list).
std::optional<ParamValue> FieldValue(const pb::Message& m, const pb::FieldDescriptor* f) {
  const pb::Reflection* r = m.GetReflection();
  using T = pb::FieldDescriptor;
  if (f->is_repeated()) {
    const int n = r->FieldSize(m, f);
    if (n == 0) return std::nullopt;
    std::vector<double> numbers;
    std::vector<int64_t> integers;
    std::vector<std::string> texts;
    for (int i = 0; i < n; ++i) {
      switch (f->cpp_type()) {
        case T::CPPTYPE_DOUBLE:
          numbers.push_back(r->GetRepeatedDouble(m, f, i));
          break;
        case T::CPPTYPE_INT32:
          integers.push_back(r->GetRepeatedInt32(m, f, i));
          break;
        case T::CPPTYPE_INT64:
          integers.push_back(r->GetRepeatedInt64(m, f, i));
          break;
        case T::CPPTYPE_STRING:
          texts.push_back(r->GetRepeatedString(m, f, i));
          break;
        default:
          return std::nullopt;
      }
    }
    if (!numbers.empty()) return ParamValue(numbers);
    if (!integers.empty()) return ParamValue(integers);
    return ParamValue(texts);
  }
  // Without presence (input.format.header_bytes), the field's zero value is unset.
  if (!r->HasField(m, f)) return std::nullopt;
  switch (f->cpp_type()) {
    case T::CPPTYPE_DOUBLE:
      return ParamValue(r->GetDouble(m, f));
    case T::CPPTYPE_INT32:
      return ParamValue(int64_t{r->GetInt32(m, f)});
    case T::CPPTYPE_INT64:
      return ParamValue(r->GetInt64(m, f));
    case T::CPPTYPE_UINT64: {
      const uint64_t u = r->GetUInt64(m, f);
      // Beyond int64 it is out of every range: say so as a number.
      if (u > uint64_t{INT64_MAX}) return ParamValue(static_cast<double>(u));
      return ParamValue(static_cast<int64_t>(u));
    }
    case T::CPPTYPE_BOOL:
      return ParamValue(r->GetBool(m, f));
    case T::CPPTYPE_STRING: {
      std::string s = r->GetString(m, f);
      if (s.empty()) return std::nullopt;
      return ParamValue(std::move(s));
    }
    default:
      return std::nullopt;
  }
}

}  // namespace

absl::StatusOr<std::string> ResolveJobParameters(const v1::PipelineParameters& p,
                                                 const v1::JobInput& input) {
  ParameterBuilder builder(ParamScope::kJob);
  if (!p.config_json().empty()) {
    SM_RETURN_IF_ERROR(builder.AddJson(p.config_json(), "parameters.config_json"));
  }
  const pb::Descriptor* format = v1::VolumeFormat::descriptor();
  for (const ParamSpec& s : Parameters()) {
    if (s.scope == ParamScope::kLocal) continue;
    const bool in_format =
        absl::StartsWith(s.key, "input.") && format->FindFieldByName(s.name()) != nullptr;
    const pb::Message& m = in_format ? static_cast<const pb::Message&>(input.format()) : p;
    const pb::FieldDescriptor* f = m.GetDescriptor()->FindFieldByName(s.name());
    if (f == nullptr) continue;  // JobParametersTest checks that every parameter has one
    std::optional<ParamValue> v = FieldValue(m, f);
    if (!v) continue;
    SM_RETURN_IF_ERROR(builder.Add(
        s, std::move(*v), absl::StrCat(in_format ? "input.format." : "parameters.", s.name())));
  }
  SM_ASSIGN_OR_RETURN(PipelineOptions o, builder.Build());
  return CanonicalParametersJson(o, /*include_local=*/false);
}

absl::StatusOr<PipelineOptions> JobPipelineOptions(const v1::Job& job,
                                                   const std::string& volume_path) {
  std::string canonical = job.resolved_parameters();
  if (canonical.empty()) {
    SM_ASSIGN_OR_RETURN(canonical, ResolveJobParameters(job.parameters(), job.input()));
  }
  return OptionsFromResolved(canonical, volume_path);
}

absl::StatusOr<PipelineOptions> OptionsFromResolved(const std::string& canonical,
                                                    const std::string& volume_path) {
  ParameterBuilder builder(ParamScope::kJob);
  SM_RETURN_IF_ERROR(builder.AddJson(canonical, "the job's resolved parameters"));
  SM_ASSIGN_OR_RETURN(PipelineOptions o, builder.Build());
  o.input.path = volume_path;
  return o;
}

absl::Status CheckBrickRequest(const std::string& bricks) {
  SM_ASSIGN_OR_RETURN(const Index3 size, ParseBrickSize(bricks, "bricks"));
  if (size.x < 0 || size.y < 0 || size.z < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("bricks '", bricks, "' has a negative edge: each is at least 1 (0: chosen)"));
  }
  // A brick task costs a process, a lease and a file whatever its size: 4x4x4 bricks of a
  // small volume were 21,504 tasks, hours of work for seconds of it (hardening, third round).
  const int64_t voxels = int64_t{size.x} * size.y * size.z;
  if (voxels > 0 && voxels < kMinJobBrickVoxels) {
    return absl::InvalidArgumentError(absl::StrCat(
        "bricks '", bricks, "' holds ", voxels, " voxels a brick, below the ", kMinJobBrickVoxels,
        " a brick task is worth (16x16x16): give larger bricks, or auto"));
  }
  return absl::OkStatus();
}

}  // namespace sheetmesh::runtime
