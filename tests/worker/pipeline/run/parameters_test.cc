#include "worker/pipeline/run/parameters.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>

#include "absl/strings/match.h"
#include "absl/strings/str_split.h"
#include "common/assert.h"
#include "tests/testing/status_matchers.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::IsOk;
using ::sheetmesh::testing::StatusIs;
using ::testing::HasSubstr;

absl::StatusOr<PipelineOptions> FromJson(const std::string& json) {
  ParameterBuilder b;
  absl::Status st = b.AddJson(json, "cfg.json");
  if (!st.ok()) return st;
  return b.Build();
}

absl::StatusOr<PipelineOptions> FromFlag(const std::string& name, const std::string& text,
                                         PipelineOptions base = {}) {
  const ParamSpec* s = FindParameter(name);
  if (s == nullptr) return absl::NotFoundError(name);
  absl::StatusOr<ParamValue> v = ParseParameterText(*s, text, "--" + s->name());
  if (!v.ok()) return v.status();
  ParameterBuilder b;
  absl::Status st = b.Add(*s, *v, "--" + s->name());
  if (!st.ok()) return st;
  return b.Build(base);
}

// A value inside the row's range (and choices), other than `avoid` where one exists.
ParamValue SomeOtherValue(const ParamSpec& s, const std::optional<ParamValue>& avoid, int k = 0) {
  auto pick = [&](double x) {
    const ParamRange& r = s.range;
    std::vector<double> tries = {
        x, 60, r.lo, r.hi, (r.lo + r.hi) / 2, std::floor((r.lo + r.hi) / 2), r.lo + 1, r.hi - 1, 0};
    tries.erase(tries.begin(), tries.begin() + std::min<size_t>(k, tries.size() - 1));
    for (double t : tries) {
      if (!r.Contains(t)) continue;
      if (s.type == ParamType::kInteger || s.type == ParamType::kIntegers) {
        if (t != std::floor(t)) continue;
      }
      if (avoid && s.type == ParamType::kNumber && std::get<double>(*avoid) == t) continue;
      if (avoid && s.type == ParamType::kInteger && std::get<int64_t>(*avoid) == int64_t(t))
        continue;
      return t;
    }
    return r.lo;
  };
  switch (s.type) {
    case ParamType::kBool:
      return avoid ? !std::get<bool>(*avoid) : true;
    case ParamType::kInteger:
      return static_cast<int64_t>(pick(3));
    case ParamType::kNumber:
      return pick((s.range.lo + s.range.hi) / 2);
    case ParamType::kChoice:
      for (const std::string& c : s.choices) {
        if (!avoid || std::get<std::string>(*avoid) != c) return c;
      }
      return s.choices[0];
    case ParamType::kText:
      // input.threshold takes otsu or a number.
      return std::string(s.key == "input.threshold" ? "otsu" : "x");
    case ParamType::kNumbers: {
      const int n = s.count > 0 ? s.count : 2;
      std::vector<double> v;
      for (int i = 0; i < n; ++i)
        v.push_back(pick(1.5) + (s.range.Contains(pick(1.5) + i) ? i : 0));
      return v;
    }
    case ParamType::kIntegers: {
      // Increasing, as boxes (input.region: the low corner, then the high) need them.
      const int n = s.count > 0 ? s.count : 1;
      std::vector<int64_t> v;
      for (int i = 0; i < n; ++i) {
        const int64_t x = static_cast<int64_t>(pick(5));
        v.push_back(s.range.Contains(x + i) ? x + i : x);
      }
      return v;
    }
    case ParamType::kChoices:
      return std::vector<std::string>{s.choices.back()};
  }
  return false;
}

TEST(ParametersTest, EveryRowHasANameADocADefaultInsideItsRangeAndOneSpelling) {
  const PipelineOptions defaults;
  std::set<std::string> names, keys;
  for (const ParamSpec& s : Parameters()) {
    SCOPED_TRACE(s.key);
    EXPECT_TRUE(keys.insert(s.key).second) << "key twice";
    EXPECT_TRUE(names.insert(s.name()).second) << "flag name twice: " << s.name();
    EXPECT_FALSE(s.doc.empty());
    EXPECT_EQ(FindParameter(s.key), &s);
    EXPECT_EQ(FindParameter(s.name()), &s);
    EXPECT_EQ(RenamedParameter(s.key), nullptr) << "a current key is also an old one";
    EXPECT_EQ(RenamedParameter(s.name()), nullptr) << "a current flag is also an old one";
    const std::optional<ParamValue> d = GetParameter(s, defaults);
    if (s.preset) {
      EXPECT_FALSE(d.has_value());
      continue;
    }
    if (!d) continue;  // an unset override (input.spacing, input.dims, ...)
    ParameterBuilder b;
    EXPECT_THAT(b.Add(s, *d, "default"), IsOk()) << "the default is outside its own range";
  }
  EXPECT_THAT(CheckParameters(defaults), IsOk());
}

TEST(ParametersTest, EveryRowRoundTripsThroughConfigJsonAndFlagText) {
  for (const ParamSpec& s : Parameters()) {
    if (s.preset) continue;
    SCOPED_TRACE(s.key);
    const PipelineOptions defaults;
    // A value the other defaults allow (improve.target_degrees must stay above
    // improve.insert_below_degrees, detect.t at most detect.R, ...).
    ParamValue v;
    absl::StatusOr<PipelineOptions> from_json;
    for (int k = 0; k < 9; ++k) {
      v = SomeOtherValue(s, GetParameter(s, defaults), k);
      // Config JSON, nested by the key path.
      nlohmann::json doc = nlohmann::json::object();
      nlohmann::json* at = &doc;
      for (absl::string_view part : absl::StrSplit(s.key, '.')) at = &(*at)[std::string(part)];
      *at = nlohmann::json::parse(ParameterValueJson(v));
      from_json = FromJson(doc.dump());
      if (from_json.ok()) break;
    }
    ASSERT_THAT(from_json, IsOk());
    std::optional<ParamValue> got = GetParameter(s, *from_json);
    ASSERT_TRUE(got.has_value());
    EXPECT_EQ(ParameterValueJson(*got), ParameterValueJson(v));
    // The flag's text form gives the same value.
    std::string text = ParameterValueJson(v);
    if (const auto* str = std::get_if<std::string>(&v)) text = *str;
    if (std::holds_alternative<std::vector<double>>(v) ||
        std::holds_alternative<std::vector<int64_t>>(v) ||
        std::holds_alternative<std::vector<std::string>>(v)) {
      text = text.substr(1, text.size() - 2);
      text.erase(std::remove(text.begin(), text.end(), '"'), text.end());
    }
    absl::StatusOr<PipelineOptions> from_flag = FromFlag(s.name(), text);
    ASSERT_THAT(from_flag, IsOk()) << text;
    got = GetParameter(s, *from_flag);
    ASSERT_TRUE(got.has_value());
    EXPECT_EQ(ParameterValueJson(*got), ParameterValueJson(v)) << text;
    // And the canonical text carries it.
    absl::StatusOr<PipelineOptions> again =
        FromJson(CanonicalParametersJson(*from_json, /*include_local=*/true));
    ASSERT_THAT(again, IsOk());
    EXPECT_EQ(CanonicalParametersJson(*again, true), CanonicalParametersJson(*from_json, true));
  }
}

TEST(ParametersTest, OutOfRangeValuesNameTheKeyAndValue) {
  for (const ParamSpec& s : Parameters()) {
    if (s.type != ParamType::kNumber && s.type != ParamType::kInteger) continue;
    SCOPED_TRACE(s.key);
    const double over = s.range.hi_open ? s.range.hi : s.range.hi * 2 + 1;
    const ParamValue v =
        s.type == ParamType::kNumber ? ParamValue(over) : ParamValue(static_cast<int64_t>(over));
    ParameterBuilder b;
    EXPECT_THAT(b.Add(s, v, "cfg.json: '" + s.key + "'"),
                StatusIs(absl::StatusCode::kInvalidArgument,
                         ::testing::AllOf(HasSubstr(s.key), HasSubstr(s.range.text))));
  }
}

// Extraction's lengths and angle out of their meaning: each names its key and value.
TEST(ParametersTest, ExtractionSettingsOutOfTheirMeaningAreRefused) {
  struct Case {
    const char* json;
    const char* key;
    const char* value;
  };
  for (const Case& c : {Case{R"({"detect": {"t": -1}})", "detect.t", "-1"},
                        Case{R"({"recover": {"t": -1}})", "recover.t", "-1"},
                        Case{R"({"detect": {"t": 4, "R": 3}})", "detect.R", "3"},
                        Case{R"({"separate": {"D_ang": 60}})", "separate.D_ang", "60"},
                        Case{R"({"separate": {"D_ang": 180}})", "separate.D_ang", "180"},
                        Case{R"({"separate": {"r": -2}})", "separate.r", "-2"}}) {
    SCOPED_TRACE(c.json);
    EXPECT_THAT(FromJson(c.json), StatusIs(absl::StatusCode::kInvalidArgument,
                                           ::testing::AllOf(HasSubstr(c.key), HasSubstr(c.value))));
  }
  EXPECT_THAT(FromJson(R"({"detect": {"t": 3, "R": 3}, "separate": {"D_ang": 91}})"), IsOk());
}

TEST(ParametersTest, ConfigSetsEveryGroup) {
  absl::StatusOr<PipelineOptions> o = FromJson(R"({
      "input": {"labels": [2, 3], "dims": [10, 20, 30], "dtype": "uint16", "spacing": [1, 1, 2]},
      "extract": true, "M": 1234, "r": 9, "target_similarity": 0.6,
      "refine": {"enabled": false, "close_radius": 2},
      "detect": {"t": 2.5, "R": 9, "rounds": 2},
      "separate": {"r": 6, "D_ang": 140},
      "remove_minor": {"enabled": false},
      "recover": {"rounds": 3},
      "surface": {"seed": 5, "method": "paper", "lloyd_tol": 0.01},
      "similarity": {"model": "vertex", "grid_rates": [2]},
      "improve": {"passes": 2, "target_degrees": 45, "insert_below_degrees": 12,
                  "floor_degrees": 25, "split_sheets_below_degrees": 9, "radius_weight": 0.25},
      "plc": {"snap_clear_voxels": 2.5, "wedge_degrees": 15, "wedge_voxels": 0.5,
              "overlap_voxels": 0.8, "overlap_degrees": 20, "lattice": 0.85},
      "output": {"formats": ["ply"], "model": false}})");
  ASSERT_THAT(o, IsOk());
  EXPECT_EQ(o->input.selection.ToString(), "labels=2,3");
  EXPECT_EQ(*o->input.open.raw_dims, (Dims{10, 20, 30}));
  EXPECT_EQ(*o->input.open.raw_dtype, DType::kUInt16);
  EXPECT_EQ(o->input.open.spacing->z, 2);
  EXPECT_TRUE(o->extract);
  EXPECT_FALSE(o->extraction.refine);
  EXPECT_EQ(o->extraction.refine_close_radius, 2);
  EXPECT_EQ(o->extraction.detect_extend.half_thickness_voxels, 2.5);
  EXPECT_EQ(o->extraction.detect_extend.max_rounds, 2);
  EXPECT_EQ(o->extraction.min_object_voxels, 1234u);
  EXPECT_EQ(o->extraction.separation.dihedral_degrees, 140);
  EXPECT_FALSE(o->extraction.remove_minor);
  EXPECT_EQ(o->extraction.recover_extend.max_rounds, 3);
  EXPECT_EQ(o->surface.scvd.radius_voxels, 9);
  EXPECT_EQ(o->surface.scvd.seed, 5u);
  EXPECT_FALSE(o->surface.dual.rim) << "method paper";
  EXPECT_TRUE(o->search_radius);
  EXPECT_EQ(o->radius_search.goal, RadiusGoal::kTargetSimilarity);
  EXPECT_EQ(o->score.height, PrismHeight::kVertex);
  EXPECT_EQ(o->radius_search.height, PrismHeight::kVertex) << "the search scores the same way";
  EXPECT_TRUE(o->output.ply);
  EXPECT_FALSE(o->output.vtp);
  EXPECT_FALSE(o->output.model);
  EXPECT_EQ(o->volume.improve.passes, 2);
  EXPECT_EQ(o->volume.improve.insert_below_degrees, 12);
  EXPECT_EQ(o->volume.improve.smoothing_floor_degrees, 25);
  EXPECT_EQ(o->volume.improve.radius_weight, 0.25);
  EXPECT_EQ(o->volume.plc.snap_clear_voxels, 2.5);
  EXPECT_EQ(o->volume.plc.overlap_degrees, 20);
}

TEST(ParametersTest, MistakesNameTheFileTheKeyAndTheValue) {
  struct Case {
    const char* json;
    const char* message;
  };
  const Case cases[] = {
      {R"({"surface": {"radius": 7}})", "unknown key 'surface.radius'"},
      {R"({"separate": {"D_ang": "wide"}})", "'separate.D_ang' = \"wide\" must be a number"},
      {R"({"separate": {"D_ang": 200}})", "'separate.D_ang' = 200"},
      {R"({"r": -1})", "'r' = -1"},
      {R"({"surface": {"method": "fast"}})", "'surface.method' = \"fast\" must be one of"},
      {R"({"input": {"window": [5, 1]}})", "'input.window' = [5.0,1.0] must be [lo, hi]"},
      {R"({"input": {"labels": [1], "window": [0, 2]}})", "exclude each other"},
      {R"({"M": -3})", "'M' = -3"},
      {R"({"detect": {"R": -3}})", "'detect.R' = -3"},
      {R"({"improve": {"passes": -1}})", "'improve.passes' = -1"},
      {R"({"improve": {"insert_below_degrees": 60}})",
       "'improve.insert_below_degrees' = 60 must be at most improve.target_degrees = 50"},
      {R"({"plc": {"lattice": 0.1}})", "'plc.lattice' = 0.1 must be a number in 0 | [0.25, 8]"},
      {R"({"surface": {"r": 7}})", "'surface.r' is now 'r'"},
      {R"({"volume_mesh": {"min_dihedral": 12}})",
       "'volume_mesh.min_dihedral' is now 'tet.min_dihedral'"},
      {R"({"volume_mesh": {"enabled": true}})", "'volume_mesh.enabled' is now 'volume_mesh'"},
      {R"({"similarity": {"grid_rates": [0]}})", "'similarity.grid_rates' = [0]"},
      {R"({"output": {"formats": ["stl"]}})", "names from ply, vtp, vtu, obj"},
      {R"({"output": {"split": true, "volume_formats": ["vtu"]}})",
       "'output.split' = true needs inp or exo among output.volume_formats"},
      {R"({"permeability": {"image_reference": 2}})", "'permeability.image_reference' = 2"},
      {R"({"surface": {"bricks": 128, "error_density": 1}})",
       "'surface.bricks' = 128 cannot be combined with surface.error_density = 1"},
      {R"({"grey": {"scales": [1, 1, 1, 1, 1, 1, 1, 1, 1]}})",
       "'grey.scales' = [1.0,1.0,1.0,1.0,1.0,1.0,1.0,1.0,1.0] must be a non-empty list of at most 8 "},
      {R"({"similarity": {"grid_rates": [1,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17]}})",
       "must be a list of at most 16 integers"},
      {R"({"output": {"formats": ["ply", "ply", "ply", "ply", "ply"]}})", "'output.formats'"},
      {R"({"permeability": {"matrix": 5e-324}})",
       "'permeability.matrix' = 5e-324 must be a number in [1e-25, 0.001]"},
      {R"({"permeability": {"body": 1e-40}})", "'permeability.body' = 1e-40 must be a number"},
      {R"({"surface": {"bricks": 1}})",
       "'surface.bricks' = 1 must be 0 (the surface built whole) or at least 32 voxels"},
      {R"({"surface": {"bricks": 40, "bricks_halo": 64}})",
       "'surface.bricks' = 40 must be at least surface.bricks_halo = 64"},
      {R"({"surface": )", "not valid JSON"},
      {R"([1, 2])", "must be an object"},
  };
  for (const Case& c : cases) {
    EXPECT_THAT(FromJson(c.json),
                StatusIs(absl::StatusCode::kInvalidArgument,
                         ::testing::AllOf(HasSubstr("cfg.json"), HasSubstr(c.message))))
        << c.json;
  }
}

// One behaviour for each place where the three old mappings disagreed.
TEST(ParametersTest, APresetNeverUndoesASettingGivenBesideIt) {
  // 0.8: a config with r = 5 and --method=paper on the command line ran r = 7.
  ParameterBuilder b;
  ASSERT_THAT(b.AddJson(R"({"r": 5, "surface": {"placement": "centroid"}})", "cfg.json"), IsOk());
  const ParamSpec& method = *FindParameter("surface.method");
  ASSERT_THAT(b.Add(method, std::string("paper"), "--surface_method"), IsOk());
  absl::StatusOr<PipelineOptions> o = b.Build();
  ASSERT_THAT(o, IsOk());
  EXPECT_EQ(o->surface.scvd.radius_voxels, 5);
  EXPECT_EQ(o->surface.placement, VertexPlacement::kCentroid) << "set explicitly";
  EXPECT_FALSE(o->surface.dual.rim) << "from the preset";
  EXPECT_EQ(o->surface.thickness, ThicknessMeasure::kAxisRuns) << "from the preset";
}

TEST(ParametersTest, SeparateRCarriesDetectAndRecoverUnlessTheyAreSet) {
  // 0.8: --r_sep and separate_r moved detect/recover r too, the config's separate.r did not.
  absl::StatusOr<PipelineOptions> json = FromJson(R"({"separate": {"r": 6}})");
  absl::StatusOr<PipelineOptions> flag = FromFlag("separate_r", "6");
  for (const auto* o : {&json, &flag}) {
    ASSERT_THAT(*o, IsOk());
    EXPECT_EQ((*o)->extraction.detect_extend.scvd_radius_voxels, 6);
    EXPECT_EQ((*o)->extraction.recover_extend.scvd_radius_voxels, 6);
  }
  absl::StatusOr<PipelineOptions> own =
      FromJson(R"({"separate": {"r": 6}, "detect": {"scvd_r": 4}})");
  ASSERT_THAT(own, IsOk());
  EXPECT_EQ(own->extraction.detect_extend.scvd_radius_voxels, 4);
  EXPECT_EQ(own->extraction.recover_extend.scvd_radius_voxels, 6);
  EXPECT_EQ(CanonicalParametersJson(*json, false), CanonicalParametersJson(*flag, false));
}

TEST(ParametersTest, OneTetgenSettingHasOneName) {
  // 0.8: tet_radius_edge_ratio (proto), volume_mesh.radius_edge_ratio (config), --tet_ratio,
  // max_radius_edge_ratio (report).
  const ParamSpec* s = FindParameter("tet.radius_edge_ratio");
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->name(), "tet_radius_edge_ratio");
  EXPECT_EQ(FindParameter("tet_radius_edge_ratio"), s);
  EXPECT_STREQ(RenamedParameter("tet_ratio"), "tet.radius_edge_ratio");
  EXPECT_STREQ(RenamedParameter("volume_mesh.radius_edge_ratio"), "tet.radius_edge_ratio");
  absl::StatusOr<PipelineOptions> o = FromFlag("tet-radius-edge-ratio", "2");
  ASSERT_THAT(o, IsOk());
  EXPECT_THAT(CanonicalParametersJson(*o, false), HasSubstr("\"radius_edge_ratio\":2.0"));
}

TEST(ParametersTest, TheSameSettingsWrittenDifferentlyGiveTheSameCanonicalText) {
  absl::StatusOr<PipelineOptions> a =
      FromJson(R"({"separate": {"r": 6}, "similarity": {"model": "vertex"}})");
  absl::StatusOr<PipelineOptions> b = FromJson(R"({"similarity.model": "vertex", "separate.r": 6.0,
                   "detect": {"scvd_r": 6}, "plc": {"lattice": 0.85}})");
  ASSERT_THAT(a, IsOk());
  ASSERT_THAT(b, IsOk());
  EXPECT_EQ(CanonicalParametersJson(*a, false), CanonicalParametersJson(*b, false));
  EXPECT_NE(CanonicalParametersJson(*a, false), CanonicalParametersJson(PipelineOptions(), false));
}

TEST(ParametersTest, AJobMayNotNameAPathOrProgram) {
  ParameterBuilder job(ParamScope::kJob);
  EXPECT_THAT(job.AddJson(R"({"tet": {"program": "/bin/sh"}})", "parameters.config_json"),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       ::testing::AllOf(HasSubstr("tet.program"), HasSubstr("a job may not"))));
  EXPECT_THAT(job.AddJson(R"({"input": {"mask": "/etc/shadow"}})", "parameters.config_json"),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("input.mask")));
  EXPECT_EQ(CanonicalParametersJson(PipelineOptions(), false).find("program"), std::string::npos);
}

TEST(ParametersTest, FlagTextForms) {
  absl::StatusOr<PipelineOptions> o = FromFlag("dims", "64x32x16");
  ASSERT_THAT(o, IsOk());
  EXPECT_EQ(*o->input.open.raw_dims, (Dims{64, 32, 16}));
  o = FromFlag("window", "10:20");
  ASSERT_THAT(o, IsOk());
  EXPECT_EQ(o->input.selection.ToString(), "window=10:20");
  o = FromFlag("output.formats", "ply,obj");
  ASSERT_THAT(o, IsOk());
  EXPECT_TRUE(o->output.ply && o->output.obj && !o->output.vtp);
  o = FromFlag("similarity.grid_rates", "");
  ASSERT_THAT(o, IsOk());
  EXPECT_TRUE(o->score.grid_rates.empty());
  EXPECT_THAT(FromFlag("r", "seven"), StatusIs(absl::StatusCode::kInvalidArgument,
                                               HasSubstr("--r=seven must be a number")));
  EXPECT_THAT(FromFlag("volume_mesh", "maybe"),
              StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("true or false")));
}

TEST(ParametersTest, TheMarkdownTableListsEveryRow) {
  const std::string md = ParametersMarkdown();
  for (const ParamSpec& s : Parameters()) {
    EXPECT_THAT(md, HasSubstr("| `" + s.key + "` | `--" + s.name() + "` |"));
  }
}

TEST(ParamRangeTest, ParsesIntervalsAsWritten) {
  const ParamRange a = ParamRange::Parse("(0, 180]");
  EXPECT_FALSE(a.Contains(0));
  EXPECT_TRUE(a.Contains(180));
  EXPECT_FALSE(a.Contains(180.5));
  const ParamRange b = ParamRange::Parse("0 | [0.25, 8]");
  EXPECT_TRUE(b.Contains(0));
  EXPECT_FALSE(b.Contains(0.1));
  EXPECT_TRUE(b.Contains(0.25));
  const ParamRange c = ParamRange::Parse("[0, 70)");
  EXPECT_TRUE(c.Contains(0));
  EXPECT_FALSE(c.Contains(70));
}

TEST(ParamRangeTest, AMalformedRangeIsABugTheTestsBuildCatches) {
#if SM_ASSERTS_ON
  EXPECT_DEATH(ParamRange::Parse("[1, "), "assertion failed");
#else
  GTEST_SKIP() << "SM_ASSERT is off in this build; tools/test.sh builds with it on";
#endif
}

}  // namespace
}  // namespace sheetmesh

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::StatusIs;
using ::testing::AllOf;
using ::testing::HasSubstr;

// Hardening, third round: a number past a double's range was an uncaught out_of_range (the
// CLI aborted; the service answered UNKNOWN).
TEST(ParametersTest, NumbersBeyondADoubleAreInvalidArgumentNamingTheirKey) {
  for (const auto& [json, key, text] :
       std::vector<std::tuple<std::string, std::string, std::string>>{
           {R"({"r": 1e999})", "'r'", "1e999"},
           {R"({"surface": {"r": -1e400}})", "'surface.r'", "-1e400"},
           {R"({"grey": {"scales": [1, 2, 1e309]}})", "'grey.scales[2]'", "1e309"}}) {
    ParameterBuilder b;
    EXPECT_THAT(b.AddJson(json, "cfg.json"),
                StatusIs(absl::StatusCode::kInvalidArgument,
                         AllOf(HasSubstr("cfg.json"), HasSubstr(key), HasSubstr(text),
                               HasSubstr("beyond the range"))))
        << json;
  }
  ParameterBuilder b;
  EXPECT_THAT(b.AddJson(R"({"r": 4,, })", "cfg.json"),
              StatusIs(absl::StatusCode::kInvalidArgument,
                       AllOf(HasSubstr("not valid JSON at 'r'"), HasSubstr("byte 9"))));
  const ParamSpec* r = FindParameter("r");
  ASSERT_NE(r, nullptr);
  absl::StatusOr<ParamValue> v = ParseParameterText(*r, "1e999", "--r");
  if (v.ok()) {
    ParameterBuilder flags;
    EXPECT_THAT(flags.Add(*r, *v, "--r"),
                StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("inf")));
  }
}

}  // namespace
}  // namespace sheetmesh
