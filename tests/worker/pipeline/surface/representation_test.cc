// Bodies and the choice of representation against known answers: a closed surface around
// voxels scores 1 at voxel resolution, a vug is a body and a thin sheet beside it stays a
// sheet, each at its share of the triangles.
#include "worker/pipeline/surface/representation.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <nlohmann/json.hpp>

#include "tests/testing/shapes.h"
#include "tests/testing/status_matchers.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/similarity/similarity.h"
#include "worker/pipeline/surface/body_surface.h"
#include "worker/pipeline/surface/surface_builder.h"
#include "worker/pipeline/tet/volume_mesher.h"

namespace sheetmesh {
namespace {

// Every edge of `mesh` in exactly two faces, in opposite directions (closed and oriented).
bool ClosedAndOriented(const TriangleMesh& mesh) {
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (const Face& f : mesh.faces) {
    for (int k = 0; k < 3; ++k) ++directed[{f[k], f[(k + 1) % 3]}];
  }
  for (const auto& [e, n] : directed) {
    if (n != 1) return false;
    auto back = directed.find({e.second, e.first});
    if (back == directed.end() || back->second != 1) return false;
  }
  return true;
}

double SignedVolume(const TriangleMesh& mesh) {
  double v = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto t = Corners(mesh, f);
    v += Dot(t[0], Cross(t[1], t[2])) / 6;
  }
  return v;
}

double BodyScore(const TriangleMesh& body, const VoxelSet& voxels) {
  return ScoreModel(*VoxelizeClosedSurface(body, voxels.dims()), voxels).similarity;
}

TEST(BodySurfaceTest, ABallAtVoxelResolutionIsExactClosedAndOutward) {
  const VoxelSet ball = testing::ShapeSet({40, 40, 40}, [](double x, double y, double z) {
    return std::hypot(x - 20, y - 19, z - 21) <= 12;
  });
  SM_ASSERT_OK_AND_ASSIGN(BodySurface b, MeshBody(ball, 7, 0));
  EXPECT_TRUE(ClosedAndOriented(b.mesh));
  EXPECT_NEAR(SignedVolume(b.mesh), double(ball.size()), 0.05 * ball.size());
  EXPECT_DOUBLE_EQ(BodyScore(b.mesh, ball), 1.0);
  EXPECT_THAT(b.mesh.face_piece, ::testing::Each(7));
  EXPECT_THAT(b.mesh.face_thickness_voxels, ::testing::Each(0.0f));
  EXPECT_EQ(b.faces_before, b.mesh.num_faces());
  // Decimated to 300 faces: still closed, still the ball.
  SM_ASSERT_OK_AND_ASSIGN(BodySurface d, MeshBody(ball, 7, 300));
  EXPECT_LE(d.mesh.num_faces(), 300u);
  EXPECT_TRUE(ClosedAndOriented(d.mesh));
  EXPECT_GE(BodyScore(d.mesh, ball), 0.95);
}

TEST(BodySurfaceTest, APieceReachingTheBoxIsClosedInTheBoxFace) {
  // A slab through the whole box along x and y: its surface lies in the box's faces there.
  const VoxelSet slab =
      testing::ShapeSet({30, 30, 30}, [](double, double, double z) { return z >= 10 && z < 20; });
  SM_ASSERT_OK_AND_ASSIGN(BodySurface b, MeshBody(slab, 0, 0));
  for (const Vec3& v : b.mesh.vertices) {
    EXPECT_GE(v.x, -0.5);
    EXPECT_LE(v.x, 29.5);
    EXPECT_GE(v.y, -0.5);
    EXPECT_LE(v.y, 29.5);
  }
  EXPECT_DOUBLE_EQ(BodyScore(b.mesh, slab), 1.0);
  // Its 12 corners' worth of box: 8 triangles describe it exactly.
  SM_ASSERT_OK_AND_ASSIGN(BodySurface d, MeshBody(slab, 0, 12));
  EXPECT_LE(d.mesh.num_faces(), 12u);
  EXPECT_DOUBLE_EQ(BodyScore(d.mesh, slab), 1.0);
}

TEST(BodySurfaceTest, AnEmptyPieceIsRefused) {
  EXPECT_THAT(
      MeshBody(VoxelSet(Dims{4, 4, 4}), 3, 0),
      testing::StatusIs(absl::StatusCode::kInvalidArgument, ::testing::HasSubstr("piece 3")));
}

// A vug 40 voxels across and a 2-voxel sheet in one volume, meshed at r with the surface's
// defaults and then each piece in its representation.
struct VugAndSheet {
  SheetAnalysis sheet;
  SurfaceResult surface;
};

VugAndSheet MeshVugAndSheet(double r) {
  VugAndSheet out;
  out.sheet = *AnalyzeSheet(testing::ShapeSet({110, 110, 70}, [](double x, double y, double z) {
    const bool vug = std::abs(x - 30) < 20 && std::abs(y - 30) < 20 && std::abs(z - 35) < 20;
    const bool sheet = z >= 34 && z < 36 && x >= 60 && x < 105 && y >= 5 && y < 105;
    return vug || sheet;
  }));
  SurfaceOptions s;
  s.scvd.radius_voxels = r;
  // Formula 3 with the sheet's thickness: the vug's would leave the sheet a handful of cells.
  s.scvd.mean_thickness_voxels = 2;
  out.surface = *BuildSurface(out.sheet, s);
  return out;
}

TEST(RepresentationTest, AVugIsABodyAndAThinSheetStaysASheet) {
  VugAndSheet v = MeshVugAndSheet(9);
  ASSERT_EQ(v.sheet.components.count(), 2u);
  const size_t faces = v.surface.mesh.num_faces();
  SM_ASSERT_OK_AND_ASSIGN(RepresentationReport report,
                          ChooseRepresentation(v.sheet, {}, {}, &v.surface.mesh));
  ASSERT_EQ(report.pieces.size(), 2u);
  EXPECT_EQ(report.bodies, 1u);
  // Components are ordered by size: the vug (64,000 voxels) is 0, the sheet 1.
  const PieceRepresentation& vug = report.pieces[0];
  const PieceRepresentation& sheet = report.pieces[1];
  EXPECT_TRUE(vug.body);
  ASSERT_TRUE(vug.body_similarity.has_value());
  EXPECT_GT(*vug.body_similarity, *vug.sheet_similarity);
  EXPECT_GE(*vug.body_similarity, 0.95);
  EXPECT_LE(vug.body_triangles, vug.sheet_triangles);
  EXPECT_FALSE(sheet.body);
  EXPECT_FALSE(sheet.body_similarity.has_value());  // 2 voxels: not tried
  EXPECT_EQ(v.surface.mesh.body_pieces, std::vector<int32_t>{0});
  EXPECT_LE(v.surface.mesh.num_faces(), faces);  // the budget holds
  // The whole model: the vug's inside and the sheet's prisms.
  SM_ASSERT_OK_AND_ASSIGN(VoxelSet model, VoxelizeMesh(v.surface.mesh, v.sheet.set.dims()));
  EXPECT_GE(ScoreModel(model, v.sheet.set).similarity, 0.93);
}

TEST(RepresentationTest, AVugAt200TrianglesScoresOver095) {
  const VoxelSet vug = testing::ShapeSet({60, 60, 60}, [](double x, double y, double z) {
    return std::abs(x - 30) < 20 && std::abs(y - 30) < 20 && std::abs(z - 30) < 20;
  });
  SM_ASSERT_OK_AND_ASSIGN(BodySurface b, MeshBody(vug, 0, 200));
  EXPECT_LE(b.mesh.num_faces(), 200u);
  EXPECT_GE(BodyScore(b.mesh, vug), 0.95);
}

TEST(RepresentationTest, ForcedEitherWay) {
  VugAndSheet sheets = MeshVugAndSheet(9);
  const TriangleMesh before = sheets.surface.mesh;
  RepresentationOptions o;
  o.mode = RepresentationMode::kSheet;
  SM_ASSERT_OK_AND_ASSIGN(RepresentationReport r,
                          ChooseRepresentation(sheets.sheet, {}, o, &sheets.surface.mesh));
  EXPECT_EQ(r.bodies, 0u);
  EXPECT_EQ(sheets.surface.mesh.faces, before.faces);
  EXPECT_TRUE(sheets.surface.mesh.body_pieces.empty());

  VugAndSheet bodies = MeshVugAndSheet(9);
  o.mode = RepresentationMode::kBody;
  SM_ASSERT_OK_AND_ASSIGN(r, ChooseRepresentation(bodies.sheet, {}, o, &bodies.surface.mesh));
  EXPECT_EQ(r.bodies, 2u);
  EXPECT_EQ(bodies.surface.mesh.body_pieces, (std::vector<int32_t>{0, 1}));
  for (size_t f = 0; f < bodies.surface.mesh.num_faces(); ++f) {
    EXPECT_TRUE(bodies.surface.mesh.IsBodyFace(f));
  }
  // Each body carries 2 V / A: the vug, a 40-voxel cube, 2 × 64,000 / 9,600; the sheet, 2 ×
  // 45 × 100 voxels, 2 × 9,000 / (9,000 + its 580 of rim).
  EXPECT_NEAR(r.pieces[0].equivalent_aperture, 2 * 64000.0 / 9600, 0.03 * 13.33);
  EXPECT_NEAR(r.pieces[1].equivalent_aperture, 2 * 9000.0 / 9580, 0.03 * 1.88);
  EXPECT_EQ(sheets.surface.mesh.body_pieces.size(), 0u);
}

// A slab 10 voxels thick from side to side of the box, as a body, has the aperture of the
// gap between its walls: its faces in the box's faces are no walls (nor are they in the
// volume mesh, whose flow gives a body the same 2 V / A).
TEST(RepresentationTest, ASlabAcrossTheBoxAsABodyHasItsThicknessForAperture) {
  SheetAnalysis sheet = *AnalyzeSheet(
      testing::ShapeSet({48, 40, 36}, [](double, double, double z) { return z >= 13 && z < 23; }));
  SurfaceOptions s;
  s.scvd.radius_voxels = 6;
  SurfaceResult surface = *BuildSurface(sheet, s);
  RepresentationOptions o;
  o.mode = RepresentationMode::kBody;
  SM_ASSERT_OK_AND_ASSIGN(RepresentationReport r,
                          ChooseRepresentation(sheet, {}, o, &surface.mesh));
  ASSERT_EQ(r.pieces.size(), 1u);
  ASSERT_TRUE(r.pieces[0].body);
  EXPECT_NEAR(r.pieces[0].equivalent_aperture, 10, 0.3);
  EXPECT_EQ(r.Fields()["pieces"][0]["equivalent_aperture_voxels"], r.pieces[0].equivalent_aperture);
}

// Three planar slabs of constant aperture 4, two crossing and one ending against both (a
// T), at 100 triangles asked: where the surface is the result, the closed surface of the junction
// is nearly exact (its walls are a dozen rectangles) and beats the sheet, whose junction
// curves hold the decimation back; where a volume mesh follows, 4 voxels thick against a
// width of 50 stays a sheet.
TEST(RepresentationTest, WhereTheSurfaceIsTheResultAPlanarJunctionIsABody) {
  auto mesh = [](bool try_thin_bodies, double* score) {
    const SheetAnalysis sheet =
        *AnalyzeSheet(testing::ShapeSet({60, 60, 60}, [](double x, double y, double z) {
          const bool inside = x >= 5 && x < 55 && y >= 5 && y < 55;
          return (z >= 29 && z < 33 && inside) ||
                 (x >= 29 && x < 33 && y >= 5 && y < 55 && z >= 5 && z < 55) ||
                 (y >= 14 && y < 18 && z >= 33 && z < 55 && x >= 31 && x < 55);
        }));
    SurfaceOptions s;
    s.scvd.radius_voxels = 4;
    s.triangles = 100;
    SurfaceResult surface = *BuildSurface(sheet, s);
    // The sheet's decimation stops short of 100 at its junction curves; the body keeps to
    // the sheet's count.
    const size_t share = surface.mesh.num_faces();
    EXPECT_LE(share, 200u);
    RepresentationOptions o;
    o.try_thin_bodies = try_thin_bodies;
    const RepresentationReport report = *ChooseRepresentation(sheet, {}, o, &surface.mesh);
    *score = ScoreModel(*VoxelizeMesh(surface.mesh, sheet.set.dims()), sheet.set).similarity;
    EXPECT_LE(surface.mesh.num_faces(), share * (1 + kTriangleTolerance));
    return report;
  };
  double result = 0, for_volume = 0;
  const RepresentationReport alone = mesh(true, &result);
  ASSERT_EQ(alone.pieces.size(), 1u);
  EXPECT_TRUE(alone.pieces[0].body);
  ASSERT_TRUE(alone.pieces[0].body_similarity.has_value());
  EXPECT_GT(*alone.pieces[0].body_similarity, *alone.pieces[0].sheet_similarity);
  EXPECT_GE(result, 0.99);
  const RepresentationReport volume = mesh(false, &for_volume);
  ASSERT_EQ(volume.pieces.size(), 1u);
  EXPECT_FALSE(volume.pieces[0].body);
  EXPECT_FALSE(volume.pieces[0].body_similarity.has_value());  // not tried
  EXPECT_LT(for_volume, result);
}

// A 2-voxel sheet opening into a lens 40 voxels across and 20 thick: the lens becomes a
// body of its own, the sheet stays a sheet around it and reaches it; the volume mesh
// conforms to both and the lens is a region of about its voxels' volume.
TEST(RepresentationTest, AThinSheetOpeningIntoALensIsASheetAndABody) {
  const SheetAnalysis sheet =
      *AnalyzeSheet(testing::ShapeSet({100, 100, 60}, [](double x, double y, double z) {
        const bool plane = std::abs(z - 30) < 1.01 && x >= 5 && x < 95 && y >= 5 && y < 95;
        const double e =
            (std::pow(x - 50, 2) + std::pow(y - 50, 2)) / 400 + std::pow(z - 30, 2) / 100;
        return plane || e <= 1;
      }));
  SurfaceOptions s;
  s.scvd.radius_voxels = 2.66;
  SurfaceResult surface = *BuildSurface(sheet, s);
  const size_t faces = surface.mesh.num_faces();
  const double sheet_only =
      ScoreModel(*VoxelizeMesh(surface.mesh, sheet.set.dims()), sheet.set).similarity;
  SM_ASSERT_OK_AND_ASSIGN(RepresentationReport report,
                          ChooseRepresentation(sheet, {}, {}, &surface.mesh));
  ASSERT_EQ(report.pieces.size(), 2u);
  EXPECT_FALSE(report.pieces[0].body);  // the sheet, median thickness 2: no trial whole
  EXPECT_FALSE(report.pieces[0].body_similarity.has_value());
  const PieceRepresentation& lens = report.pieces[1];
  EXPECT_TRUE(lens.body);
  EXPECT_EQ(lens.part_of, 0);
  EXPECT_EQ(lens.piece, 1);
  EXPECT_EQ(surface.mesh.body_pieces, std::vector<int32_t>{1});
  EXPECT_LE(surface.mesh.num_faces(), faces);
  const double both =
      ScoreModel(*VoxelizeMesh(surface.mesh, sheet.set.dims()), sheet.set).similarity;
  EXPECT_GT(both, sheet_only);
  EXPECT_GE(both, 0.97);
  SM_ASSERT_OK_AND_ASSIGN(VolumeMeshResult volume,
                          BuildVolumeMesh(surface.mesh, sheet.set.dims(), {}, {}));
  EXPECT_EQ(volume.conformity.conforming, volume.conformity.sheet_triangles);
  EXPECT_EQ(volume.repaired_triangles, 0u);
  ASSERT_EQ(volume.bodies.size(), 1u);
  // The body is the lens's part at least 4 voxels thick (body_min_thickness).
  EXPECT_NEAR(volume.bodies[0].volume, double(lens.voxels), 0.1 * lens.voxels);
  EXPECT_GE(volume.quality.min_dihedral.min, 10.0);
}

// Two pieces (as extraction labels them): a vug and a thin sheet running through it. A body
// there would need the sheet to end on its walls from both sides; the vug stays a sheet.
// Without the sheet the same vug is a body; and a long crossing-like bar, thick but 8 times
// longer than thick, is not stout.
TEST(RepresentationTest, APieceAnotherRunsThroughAndAThinBarStaySheets) {
  auto vug = [](double x, double y, double z) {
    return std::abs(x - 40) < 15 && std::abs(y - 40) < 15 && std::abs(z - 30) < 15;
  };
  auto plane = [](double x, double y, double z) {
    return std::abs(z - 30) < 1.01 && x >= 5 && x < 95 && y >= 5 && y < 75;
  };
  const SheetAnalysis both = *AnalyzeSheet(testing::ShapeSet(
      {100, 80, 60}, [&](double x, double y, double z) { return vug(x, y, z) || plane(x, y, z); }));
  std::vector<int32_t> label(both.set.size());
  both.set.ForEachVoxel(
      [&](uint64_t i, int32_t x, int32_t y, int32_t z) { label[i] = vug(x, y, z) ? 0 : 1; });
  SurfaceOptions s;
  s.scvd.radius_voxels = 4;
  s.scvd.mean_thickness_voxels = 2;
  SurfaceResult crossed = *BuildSurface(both, s, label);
  SM_ASSERT_OK_AND_ASSIGN(RepresentationReport r,
                          ChooseRepresentation(both, label, {}, &crossed.mesh));
  EXPECT_EQ(r.bodies, 0u);

  const SheetAnalysis alone = *AnalyzeSheet(testing::ShapeSet({100, 80, 60}, vug));
  SurfaceResult single = *BuildSurface(alone, s);
  SM_ASSERT_OK_AND_ASSIGN(r, ChooseRepresentation(alone, {}, {}, &single.mesh));
  EXPECT_EQ(r.bodies, 1u);

  // 80 x 10 x 10: thick (τ 10) but eight times longer.
  const SheetAnalysis bar =
      *AnalyzeSheet(testing::ShapeSet({100, 40, 40}, [](double x, double y, double z) {
        return x >= 10 && x < 90 && std::abs(y - 20) < 5 && std::abs(z - 20) < 5;
      }));
  SurfaceResult bar_mesh = *BuildSurface(bar, s);
  SM_ASSERT_OK_AND_ASSIGN(r, ChooseRepresentation(bar, {}, {}, &bar_mesh.mesh));
  EXPECT_EQ(r.bodies, 0u);
  ASSERT_EQ(r.pieces.size(), 1u);
  EXPECT_FALSE(r.pieces[0].body_similarity.has_value());  // not tried
}

TEST(RepresentationTest, AMeshWithoutPiecesIsRefused) {
  VugAndSheet v = MeshVugAndSheet(9);
  v.surface.mesh.face_piece.clear();
  EXPECT_THAT(ChooseRepresentation(v.sheet, {}, {}, &v.surface.mesh),
              testing::StatusIs(absl::StatusCode::kInvalidArgument, ::testing::HasSubstr("piece")));
}

}  // namespace
}  // namespace sheetmesh
