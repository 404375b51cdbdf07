// Extraction against the phantom presets' ground truth: the thick rough slab and the rough
// crossing network (phantom_presets.h), whose answers are known.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "common/orientation.h"
#include "tests/testing/shapes.h"
#include "tests/testing/status_matchers.h"
#include "worker/pipeline/extract/extraction.h"
#include "worker/pipeline/extract/piece_geology.h"
#include "worker/pipeline/phantom/phantom.h"
#include "worker/pipeline/phantom/phantom_presets.h"
#include "worker/pipeline/voxel/thickness.h"

namespace sheetmesh {
namespace {

struct Preset {
  PhantomTruth truth;
  VoxelSet phase;   // every non-zero voxel
  VoxelSet sheets;  // the sheets' voxels only (specks drawn apart)
};

Preset Make(const std::string& name) {
  Preset p;
  absl::StatusOr<PhantomOptions> o = PhantomPreset(name);
  EXPECT_TRUE(o.ok()) << o.status();
  PhantomOptions no_specks = *o;
  no_specks.num_specks = 0;
  auto phase_of = [](const PhantomOptions& options, PhantomTruth* truth) {
    absl::StatusOr<PhantomTruth> t = PlanPhantom(options);
    EXPECT_TRUE(t.ok()) << t.status();
    *truth = *t;
    absl::StatusOr<DenseVolume> v = GeneratePhantomDense(truth);
    EXPECT_TRUE(v.ok()) << v.status();
    VoxelSet::Builder b(options.dims);
    for (int z = 0; z < options.dims.nz; ++z)
      for (int y = 0; y < options.dims.ny; ++y)
        for (int x = 0; x < options.dims.nx; ++x)
          if (v->At(x, y, z) != 0) b.AddVoxel(x, y, z);
    return std::move(b).Build();
  };
  PhantomTruth sheets_only;
  p.phase = phase_of(*o, &p.truth);
  p.sheets = phase_of(no_specks, &sheets_only);
  return p;
}

std::vector<PieceGeology> Geology(const LabelledVoxels& m) {
  return ComputePieceGeology(m, *ComputeThickness(m.set), TriangleMesh{}, Placement{});
}

// The voxels of the true sheets the model kept.
double Kept(const Preset& p, const ExtractionResult& r) {
  return double(Intersection(p.sheets, r.model.set).size()) / p.sheets.size();
}

TEST(ExtractionPresetsTest, ThickRoughSlabStaysOnePieceAndWhole) {
  const Preset p = Make("thick_slab");
  SM_ASSERT_OK_AND_ASSIGN(ExtractionResult r, ExtractFeatures(p.phase, {}));
  const std::vector<PieceGeology> g = Geology(r.model);
  ASSERT_GE(g.size(), 1u);
  EXPECT_EQ(g.size(), 1u) << "one slab, one piece";
  EXPECT_LE(AngleBetweenNormalsDegrees(g[0].normal, p.truth.sheets[0].normal), 5.0);
  EXPECT_GE(Kept(p, r), 0.98);
}

TEST(ExtractionPresetsTest, SeparationKeepsTheRoughThickSlabWhole) {
  // At the r extraction uses for this slab (t / 2) the SCVD grows over columns whose axis
  // is voted for over a thickness-wide neighbourhood, so its rough walls no longer fold the
  // triangles: neither the fit over two rings nor the paper's single-triangle test cuts it
  // (before the vote the paper's test cut over a tenth of it).
  const Preset p = Make("thick_slab");
  SeparationOptions o;
  o.radius_voxels =
      std::max(kSeparationRadiusFloor, SummarizeThickness(*ComputeThickness(p.sheets)).mean / 2);
  SM_ASSERT_OK_AND_ASSIGN(SeparationResult fitted, Separate(p.sheets, o));
  EXPECT_LE(fitted.removed_voxels, p.sheets.size() / 100);
  o.fit_rings = 0;
  SM_ASSERT_OK_AND_ASSIGN(SeparationResult paper, Separate(p.sheets, o));
  EXPECT_LE(paper.removed_voxels, p.sheets.size() / 100);
}

TEST(ExtractionPresetsTest, RoughCrossingNetworkGivesItsFourSheets) {
  const Preset p = Make("rough_network");
  SM_ASSERT_OK_AND_ASSIGN(ExtractionResult r, ExtractFeatures(p.phase, {}));
  const std::vector<PieceGeology> g = Geology(r.model);
  for (size_t k = 0; k < p.truth.sheets.size(); ++k) {
    const PhantomSheet& s = p.truth.sheets[k];
    double best = 180;
    for (const PieceGeology& piece : g) {
      if (piece.voxels < s.voxels / 10) continue;
      best = std::min(best, AngleBetweenNormalsDegrees(piece.normal, s.normal));
    }
    EXPECT_LE(best, 10.0) << "sheet " << k;
  }
  EXPECT_GE(Kept(p, r), 0.95);
  // Pieces a crossing split share their sheet's id: four sheets, each in one true plane.
  std::map<int32_t, std::vector<const PieceGeology*>> sheets;
  for (const PieceGeology& piece : g) sheets[piece.sheet].push_back(&piece);
  EXPECT_EQ(sheets.size(), 4u);
  std::set<size_t> truths;
  for (const auto& [id, members] : sheets) {
    size_t nearest = 0;
    for (size_t k = 0; k < p.truth.sheets.size(); ++k) {
      if (AngleBetweenNormalsDegrees(members[0]->normal, p.truth.sheets[k].normal) <
          AngleBetweenNormalsDegrees(members[0]->normal, p.truth.sheets[nearest].normal)) {
        nearest = k;
      }
    }
    for (const PieceGeology* m : members) {
      EXPECT_LE(AngleBetweenNormalsDegrees(m->normal, p.truth.sheets[nearest].normal), 10.0)
          << "sheet " << id << " piece " << m->piece;
    }
    truths.insert(nearest);
  }
  EXPECT_EQ(truths.size(), 4u) << "each sheet id is another true sheet";
}

TEST(ExtractionPresetsTest, RetentionAccountsForEveryVoxelOnce) {
  const Preset p = Make("rough_network");
  SM_ASSERT_OK_AND_ASSIGN(ExtractionResult r, ExtractFeatures(p.phase, {}));
  const ExtractionRetention& t = r.retention;
  EXPECT_EQ(t.input_voxels, p.phase.size());
  EXPECT_EQ(t.kept + t.dropped_by_refine + t.dropped_specks + t.dropped_at_crossings +
                t.dropped_minor_pieces,
            t.input_voxels);
  EXPECT_EQ(t.kept, Intersection(p.phase, r.model.set).size());
  uint64_t per_piece = 0;
  for (uint64_t n : t.kept_per_piece) per_piece += n;
  EXPECT_EQ(per_piece, t.kept);
  EXPECT_EQ(t.kept_per_piece.size(), r.model.CountLabels());
  // The specks are small objects: detection drops them.
  EXPECT_GT(t.dropped_specks, 0u);
  // The dropped voxels, labelled by why, are the rest of the phase.
  EXPECT_EQ(r.dropped.set, Difference(p.phase, r.model.set));
  std::map<int32_t, uint64_t> why;
  for (int32_t l : r.dropped.label) ++why[l];
  EXPECT_EQ(why[static_cast<int32_t>(DroppedBy::kRefine)], t.dropped_by_refine);
  EXPECT_EQ(why[static_cast<int32_t>(DroppedBy::kSpeck)], t.dropped_specks);
  EXPECT_EQ(why[static_cast<int32_t>(DroppedBy::kCrossing)], t.dropped_at_crossings);
  EXPECT_EQ(why[static_cast<int32_t>(DroppedBy::kMinorPiece)], t.dropped_minor_pieces);
  // Recovery stopped because nothing more could be added, not on a cap.
  EXPECT_GT(r.steps[4].rounds, 0);
}

const DerivedValue* Used(const ExtractionResult& r, const std::string& key) {
  for (const DerivedValue& d : r.derived) {
    if (d.key == key) return &d;
  }
  return nullptr;
}

TEST(ExtractionPresetsTest, SeparationRadiusFollowsTheThicknessUnlessSet) {
  // A slab 30 voxels thick: every voxel's τ is 30, so r = max(5, 30 / 2) = 15 and
  // M = 3 · 30 · (1 + 2 · 15 · 14) = 37,890.
  const Dims d{96, 96, 48};
  const VoxelSet slab = testing::BoxSet(d, {0, 0, 9}, {96, 96, 39});
  ExtractionOptions o;
  o.refine = false;
  SM_ASSERT_OK_AND_ASSIGN(ExtractionResult r, ExtractFeatures(slab, o));
  ASSERT_NE(Used(r, "separate.r"), nullptr);
  EXPECT_DOUBLE_EQ(Used(r, "separate.r")->value, 15.0);
  EXPECT_THAT(Used(r, "separate.r")->from, ::testing::HasSubstr("t = 30"));
  ASSERT_NE(Used(r, "M"), nullptr);
  EXPECT_DOUBLE_EQ(Used(r, "M")->value, 37890.0);
  // Detection's cylinder follows r: t = 0.3 r = 4.5, R = 1.4 r = 21.
  EXPECT_DOUBLE_EQ(Used(r, "detect.t")->value, 4.5);
  EXPECT_DOUBLE_EQ(Used(r, "detect.R")->value, 21.0);
  EXPECT_THAT(Used(r, "detect.R")->from, ::testing::HasSubstr("separate.r"));
  EXPECT_EQ(r.model.CountLabels(), 1u);
  EXPECT_EQ(r.retention.kept, slab.size());
  // A user's value is used as given, and said to be; what follows it keeps R >= t.
  o.separation.radius_voxels = 8;
  o.min_object_voxels = 1000;
  o.detect_extend.half_thickness_voxels = 12;
  SM_ASSERT_OK_AND_ASSIGN(ExtractionResult set, ExtractFeatures(slab, o));
  EXPECT_DOUBLE_EQ(Used(set, "separate.r")->value, 8.0);
  EXPECT_EQ(Used(set, "separate.r")->from, "set");
  EXPECT_DOUBLE_EQ(Used(set, "M")->value, 1000.0);
  EXPECT_EQ(Used(set, "M")->from, "set");
  EXPECT_DOUBLE_EQ(Used(set, "detect.t")->value, 12.0);
  EXPECT_EQ(Used(set, "detect.t")->from, "set");
  EXPECT_DOUBLE_EQ(Used(set, "detect.R")->value, 12.0);  // max(1.4 · 8, t)
}

TEST(ExtractionPresetsTest, EveryPresetIsKnownAndAnUnknownOneIsNamed) {
  for (const std::string& name : PhantomPresetNames()) {
    SM_ASSERT_OK_AND_ASSIGN(PhantomOptions o, PhantomPreset(name));
    EXPECT_TRUE(PlanPhantom(o).ok()) << name;
  }
  EXPECT_THAT(PhantomPreset("granite"),
              testing::StatusIs(absl::StatusCode::kInvalidArgument,
                                ::testing::AllOf(::testing::HasSubstr("granite"),
                                                 ::testing::HasSubstr("thick_slab"))));
}

}  // namespace
}  // namespace sheetmesh
