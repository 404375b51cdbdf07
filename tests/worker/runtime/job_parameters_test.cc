#include "worker/runtime/job_parameters.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <set>

#include "absl/strings/match.h"
#include "absl/strings/str_split.h"
#include "tests/testing/status_matchers.h"
#include "worker/pipeline/run/parameters.h"

namespace sheetmesh::runtime {
namespace {

namespace pb = ::google::protobuf;
using ::sheetmesh::testing::IsOk;
using ::sheetmesh::testing::StatusIs;
using ::testing::HasSubstr;

// The proto field that carries parameter `s`, or null.
const pb::FieldDescriptor* FieldOf(const ParamSpec& s) {
  if (absl::StartsWith(s.key, "input.")) {
    if (const auto* f = v1::VolumeFormat::descriptor()->FindFieldByName(s.name())) return f;
  }
  return v1::PipelineParameters::descriptor()->FindFieldByName(s.name());
}

bool TypeFits(const ParamSpec& s, const pb::FieldDescriptor* f) {
  using T = pb::FieldDescriptor;
  const bool list = s.type == ParamType::kNumbers || s.type == ParamType::kIntegers ||
                    s.type == ParamType::kChoices;
  if (list != f->is_repeated()) return false;
  switch (s.type) {
    case ParamType::kBool:
      return f->cpp_type() == T::CPPTYPE_BOOL && f->has_presence();
    case ParamType::kInteger:
    case ParamType::kIntegers:
      return (f->cpp_type() == T::CPPTYPE_INT32 || f->cpp_type() == T::CPPTYPE_INT64 ||
              f->cpp_type() == T::CPPTYPE_UINT64) &&
             (list || f->has_presence() || s.key == "input.header_bytes");
    case ParamType::kNumber:
    case ParamType::kNumbers:
      return f->cpp_type() == T::CPPTYPE_DOUBLE && (list || f->has_presence());
    case ParamType::kChoice:
    case ParamType::kText:
    case ParamType::kChoices:
      return f->cpp_type() == T::CPPTYPE_STRING;
  }
  return false;
}

TEST(JobParametersTest, EveryJobParameterHasOneProtoFieldOfItsNameAndType) {
  std::set<std::string> covered;
  for (const ParamSpec& s : Parameters()) {
    SCOPED_TRACE(s.key);
    const pb::FieldDescriptor* f = FieldOf(s);
    if (s.scope == ParamScope::kLocal) {
      EXPECT_EQ(f, nullptr) << "a job may not set it, so the proto should not offer it";
      continue;
    }
    ASSERT_NE(f, nullptr) << "no proto field " << s.name();
    EXPECT_TRUE(TypeFits(s, f)) << f->full_name() << " has the wrong type or no presence";
    covered.insert(f->full_name());
  }
  for (const pb::Descriptor* d :
       {v1::PipelineParameters::descriptor(), v1::VolumeFormat::descriptor()}) {
    for (int i = 0; i < d->field_count(); ++i) {
      const pb::FieldDescriptor* f = d->field(i);
      if (f->name() == "config_json") continue;
      EXPECT_TRUE(covered.count(f->full_name())) << f->full_name() << " is no parameter";
    }
  }
}

// Sets `f` of `m` to a value for parameter `s` (candidate `k` of a few) and returns the
// same value as config JSON; "" when there is no candidate `k`.
std::string SetCandidate(const ParamSpec& s, const pb::FieldDescriptor* f, pb::Message* m, int k) {
  using T = pb::FieldDescriptor;
  const pb::Reflection* r = m->GetReflection();
  const std::optional<ParamValue> d = GetParameter(s, PipelineOptions());
  switch (s.type) {
    case ParamType::kBool: {
      if (k > 0) return "";
      const bool v = !(d && std::get<bool>(*d));
      r->SetBool(m, f, v);
      return v ? "true" : "false";
    }
    case ParamType::kInteger: {
      const int64_t tries[] = {3, 1 << 30, 1, 64};
      if (k >= 4) return "";
      const int64_t v = tries[k];
      if (!s.range.Contains(double(v)) || (d && std::get<int64_t>(*d) == v)) return "skip";
      if (f->cpp_type() == T::CPPTYPE_INT32) r->SetInt32(m, f, int32_t(v));
      if (f->cpp_type() == T::CPPTYPE_INT64) r->SetInt64(m, f, v);
      if (f->cpp_type() == T::CPPTYPE_UINT64) r->SetUInt64(m, f, uint64_t(v));
      return std::to_string(v);
    }
    case ParamType::kNumber: {
      const double tries[] = {0.75, 1.5, 45, 60, (s.range.lo + s.range.hi) / 2};
      if (k >= 5) return "";
      const double v = tries[k];
      if (!s.range.Contains(v) || (d && std::get<double>(*d) == v)) return "skip";
      r->SetDouble(m, f, v);
      return ParameterValueJson(v);
    }
    case ParamType::kChoice:
    case ParamType::kText: {
      if (k > 1) return "";
      // A word, then a number for the fields that take numbers as text (input.threshold).
      std::string v = k == 0 ? "x" : "1";
      for (const std::string& c : s.choices) {
        if (!d || std::get<std::string>(*d) != c) v = c;
      }
      r->SetString(m, f, v);
      return "\"" + v + "\"";
    }
    case ParamType::kNumbers: {
      if (k > 0) return "";
      const int n = s.count > 0 ? s.count : 1;
      std::string json = "[";
      for (int i = 0; i < n; ++i) {
        r->AddDouble(m, f, 1 + i);
        json += (i ? "," : "") + std::to_string(1 + i);
      }
      return json + "]";
    }
    case ParamType::kIntegers: {
      if (k > 0) return "";
      const int n = s.count > 0 ? s.count : 1;
      std::string json = "[";
      for (int i = 0; i < n; ++i) {
        if (f->cpp_type() == T::CPPTYPE_INT32) r->AddInt32(m, f, 5 + i);
        if (f->cpp_type() == T::CPPTYPE_INT64) r->AddInt64(m, f, 5 + i);
        json += (i ? "," : "") + std::to_string(5 + i);
      }
      return json + "]";
    }
    case ParamType::kChoices:
      if (k > 0) return "";
      r->AddString(m, f, s.choices.front());
      return "[\"" + s.choices.front() + "\"]";
  }
  return "";
}

TEST(JobParametersTest, EveryJobParameterRoundTripsThroughItsProtoField) {
  // A value set through the field by reflection gives the same canonical settings as the
  // same value through config_json, and differs from the defaults.
  const std::string defaults = *ResolveJobParameters({}, {});
  for (const ParamSpec& s : Parameters()) {
    if (s.scope == ParamScope::kLocal || s.preset) continue;
    SCOPED_TRACE(s.key);
    const pb::FieldDescriptor* f = FieldOf(s);
    ASSERT_NE(f, nullptr);
    bool tried = false;
    for (int k = 0;; ++k) {
      v1::PipelineParameters p;
      v1::JobInput input;
      pb::Message* m = f->containing_type() == v1::VolumeFormat::descriptor()
                           ? static_cast<pb::Message*>(input.mutable_format())
                           : &p;
      const std::string json = SetCandidate(s, f, m, k);
      if (json.empty()) break;
      if (json == "skip") continue;
      absl::StatusOr<std::string> typed = ResolveJobParameters(p, input);
      if (!typed.ok()) continue;  // breaks a relation with a default (r_max below r_min)
      tried = true;
      std::string doc = json;
      std::vector<std::string> parts = absl::StrSplit(s.key, '.');
      for (auto it = parts.rbegin(); it != parts.rend(); ++it) {
        doc = "{\"" + *it + "\": " + doc + "}";
      }
      v1::PipelineParameters from_config;
      from_config.set_config_json(doc);
      absl::StatusOr<std::string> configured = ResolveJobParameters(from_config, v1::JobInput());
      ASSERT_THAT(configured, IsOk()) << doc;
      EXPECT_EQ(*typed, *configured) << doc;
      EXPECT_NE(*typed, defaults) << "the field changed nothing: " << doc;
      break;
    }
    EXPECT_TRUE(tried) << "no value of the field could be tried";
  }
}

TEST(JobParametersTest, TypedFieldsOverrideTheConfigAndErrorsNameTheField) {
  v1::PipelineParameters p;
  p.set_config_json(R"({"r": 9, "separate": {"r": 6}})");
  p.set_r(5);
  absl::StatusOr<std::string> c = ResolveJobParameters(p, {});
  ASSERT_THAT(c, IsOk());
  EXPECT_THAT(*c, HasSubstr("\"r\":5.0"));
  v1::Job job;
  job.set_resolved_parameters(*c);
  absl::StatusOr<PipelineOptions> o = JobPipelineOptions(job, "/data/rock.raw");
  ASSERT_THAT(o, IsOk());
  EXPECT_EQ(o->surface.scvd.radius_voxels, 5);
  EXPECT_EQ(o->extraction.separation.radius_voxels, 6);
  EXPECT_EQ(o->input.path, "/data/rock.raw");

  v1::PipelineParameters bad;
  bad.set_refine_close_radius(-1);
  EXPECT_THAT(ResolveJobParameters(bad, {}),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       HasSubstr("parameters.refine_close_radius = -1")));
  v1::JobInput input;
  input.mutable_format()->add_dims(4);
  EXPECT_THAT(ResolveJobParameters({}, input),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       HasSubstr("input.format.dims = [4] must be 3 integers")));
  v1::PipelineParameters huge;
  huge.set_m(~uint64_t{0});
  EXPECT_THAT(ResolveJobParameters(huge, {}),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("parameters.M")));
}

}  // namespace
}  // namespace sheetmesh::runtime
