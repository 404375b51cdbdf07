// The permeability tensor against known answers: planar fractures of aperture a through a
// cube of side L add a³/(12 L) (I − n nᵀ) (times the fracture's area over L²) to the rock's
// k_m, on real volume meshes (TetGen through BuildVolumeMesh).
#include "worker/pipeline/flow/permeability.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "tests/testing/status_matchers.h"
#include "tests/worker/pipeline/tet/tet_test_shapes.h"
#include "worker/pipeline/flow/image_permeability.h"
#include "worker/pipeline/tet/volume_mesher.h"

namespace sheetmesh {
namespace {

using ::testing::HasSubstr;

constexpr int kSide = 20;              // voxels
constexpr double kVoxelMm = 0.01;      // 10 µm voxels
constexpr double kApertureVoxels = 2;  // 20 µm
constexpr double kMatrix = 1e-18;      // m²

// A sheet over the box's face-to-face square (u, v) ∈ [−0.5, 19.5]² of the plane `at`
// (voxel coordinates), in n × n squares of two triangles, of the test's aperture.
TriangleMesh Sheet(const std::function<Vec3(double, double)>& at, int n, int32_t piece) {
  return testing::Grid(at, -0.5, kSide - 0.5, n, piece, kApertureVoxels);
}

TetMesh Mesh(const TriangleMesh& sheets) {
  Placement p;
  p.spacing = {kVoxelMm, kVoxelMm, kVoxelMm};
  p.unit = "mm";
  auto r = BuildVolumeMesh(sheets, {kSide, kSide, kSide}, p, {});
  EXPECT_TRUE(r.ok()) << r.status();
  return r->mesh;
}

// a³ / (12 L) in m² for the test's fracture through the whole cube (area L²).
double FractureTerm() {
  const double a = kApertureVoxels * kVoxelMm * 1e-3, l = kSide * kVoxelMm * 1e-3;
  return a * a * a / (12 * l);
}

FlowOptions Options() {
  FlowOptions o;
  o.enabled = true;
  o.matrix_permeability = kMatrix;
  return o;
}

TEST(PermeabilityTest, APlanarFractureAddsTheCubicLawAlongItAndNothingAcross) {
  const TetMesh mesh = Mesh(Sheet([](double u, double v) { return Vec3(u, v, 9.5); }, 4, 0));
  SM_ASSERT_OK_AND_ASSIGN(const PermeabilityResult k, SolvePermeability(mesh, Options()));
  const double along = kMatrix + FractureTerm();
  EXPECT_NEAR(k.tensor[0][0], along, 0.01 * along);
  EXPECT_NEAR(k.tensor[1][1], along, 0.01 * along);
  EXPECT_NEAR(k.tensor[2][2], kMatrix, 0.01 * kMatrix);
  EXPECT_NEAR(k.tensor[0][1], 0, 1e-3 * along);
  EXPECT_NEAR(k.tensor[0][2], 0, 1e-3 * along);
  EXPECT_GT(k.sheet_faces, 0u);
  EXPECT_NEAR(k.fracture_share[0], FractureTerm() / along, 1e-3);
  EXPECT_LE(k.residual, 1e-8);
  // Principal values largest first, the smallest across the fracture.
  EXPECT_NEAR(k.principal[0], along, 0.01 * along);
  EXPECT_NEAR(std::abs(k.principal_directions[2].z), 1, 1e-6);
}

// A scan whose unit is the inch (ImageJ writes "inch" where a scanner's resolution is in
// dots per inch) gives the same permeability in m² as the same rock in millimetres.
TEST(PermeabilityTest, AMeshInInchesGivesThePermeabilityOfTheSameRockInMillimetres) {
  const TetMesh mm = Mesh(Sheet([](double u, double v) { return Vec3(u, v, 9.5); }, 4, 0));
  TetMesh inches = mm;
  inches.unit = "inch";
  for (Vec3& p : inches.nodes) p = p / 25.4;
  inches.voxel_length /= 25.4;
  SM_ASSERT_OK_AND_ASSIGN(const PermeabilityResult a, SolvePermeability(mm, Options()));
  SM_ASSERT_OK_AND_ASSIGN(const PermeabilityResult b, SolvePermeability(inches, Options()));
  EXPECT_DOUBLE_EQ(b.metres_per_unit, 0.0254);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(b.tensor[i][i], a.tensor[i][i], 1e-6 * a.tensor[i][i]);
}

// The fields for volume.vtu: the pressure of the x solve is −x everywhere (the linear
// solution), and the velocity along a sheet face is a²/12 along x, in the rock k_m.
TEST(PermeabilityTest, TheFieldsAreTheLinearSolution) {
  const TetMesh mesh = Mesh(Sheet([](double u, double v) { return Vec3(u, v, 9.5); }, 4, 0));
  VolumeFields fields;
  ASSERT_THAT(SolvePermeability(mesh, Options(), {}, &fields).status(), testing::IsOk());
  ASSERT_EQ(fields.node_scalars.size(), 3u);
  ASSERT_EQ(fields.cell_vectors.size(), 3u);
  EXPECT_EQ(fields.node_scalars[0].first, "pressure_x");
  EXPECT_EQ(fields.cell_vectors[2].first, "velocity_z");
  const double m = 1e-3;  // the mesh's millimetres in metres
  for (size_t i = 0; i < mesh.nodes.size(); ++i) {
    ASSERT_NEAR(fields.node_scalars[0].second[i], -mesh.nodes[i].x * m,
                1e-6 * kSide * kVoxelMm * m);
  }
  const double a = kApertureVoxels * kVoxelMm * m;
  size_t sheet_faces = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Vec3 v = fields.cell_vectors[0].second[mesh.tets.size() + f];
    if (mesh.face_piece[f] < 0) {
      EXPECT_EQ(Norm(v), 0);
      continue;
    }
    ++sheet_faces;
    EXPECT_NEAR(v.x, a * a / 12, 1e-4 * a * a / 12);
    EXPECT_NEAR(v.y, 0, 1e-4 * a * a / 12);
  }
  EXPECT_GT(sheet_faces, 0u);
  EXPECT_NEAR(fields.cell_vectors[0].second[0].x, kMatrix, 1e-4 * kMatrix);
}

// Tilted 30° about y: the tensor turns with the fracture, which is 1/cos 30° longer in the
// cube.
TEST(PermeabilityTest, ATiltedFractureTurnsTheTensorWithIt) {
  const double t = std::tan(30 * M_PI / 180);
  const double c = (kSide - 1) / 2.0;
  const TetMesh mesh =
      Mesh(Sheet([&](double u, double v) { return Vec3(u, v, c - t * (u - c)); }, 4, 0));
  SM_ASSERT_OK_AND_ASSIGN(const PermeabilityResult k, SolvePermeability(mesh, Options()));
  const double along = kMatrix + FractureTerm() / std::cos(30 * M_PI / 180);
  EXPECT_NEAR(k.principal[0], along, 0.01 * along);
  EXPECT_NEAR(k.principal[1], along, 0.01 * along);
  EXPECT_NEAR(k.principal[2], kMatrix, 0.05 * kMatrix);
  const Vec3 normal = Normalized(Vec3(std::sin(30 * M_PI / 180), 0, std::cos(30 * M_PI / 180)));
  const double angle =
      std::acos(std::min(1.0, std::abs(Dot(k.principal_directions[2], normal)))) * 180 / M_PI;
  EXPECT_LE(angle, 1.0);
}

// Two orthogonal fractures crossing along y: K = k_m I + Σ a³/(12 L) (I − n nᵀ).
TEST(PermeabilityTest, TwoOrthogonalFracturesAddTheirTerms) {
  const TriangleMesh horizontal = Sheet([](double u, double v) { return Vec3(u, v, 9.5); }, 4, 0);
  const TriangleMesh vertical = Sheet([](double u, double v) { return Vec3(9.5, u, v); }, 4, 1);
  const TetMesh mesh = Mesh(testing::Append(horizontal, vertical));
  SM_ASSERT_OK_AND_ASSIGN(const PermeabilityResult k, SolvePermeability(mesh, Options()));
  const double f = FractureTerm();
  EXPECT_NEAR(k.tensor[0][0], kMatrix + f, 0.02 * (kMatrix + f));
  EXPECT_NEAR(k.tensor[1][1], kMatrix + 2 * f, 0.02 * (kMatrix + 2 * f));
  EXPECT_NEAR(k.tensor[2][2], kMatrix + f, 0.02 * (kMatrix + f));
}

// A finer sheet mesh (the triangles' size halved) gives the same tensor.
TEST(PermeabilityTest, RefiningTheMeshChangesLittle) {
  auto plane = [](double u, double v) { return Vec3(u, v, 9.5); };
  SM_ASSERT_OK_AND_ASSIGN(const PermeabilityResult coarse,
                          SolvePermeability(Mesh(Sheet(plane, 4, 0)), Options()));
  SM_ASSERT_OK_AND_ASSIGN(const PermeabilityResult fine,
                          SolvePermeability(Mesh(Sheet(plane, 8, 0)), Options()));
  EXPECT_NEAR(fine.tensor[0][0], coarse.tensor[0][0], 0.02 * coarse.tensor[0][0]);
}

TEST(PermeabilityTest, WithoutSheetsTheRockAloneAndANote) {
  const TetMesh mesh = Mesh(TriangleMesh{});
  SM_ASSERT_OK_AND_ASSIGN(const PermeabilityResult k, SolvePermeability(mesh, Options()));
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(k.tensor[i][i], kMatrix, 1e-6 * kMatrix);
  EXPECT_THAT(k.note, HasSubstr("no sheet face"));
}

// A body takes the parallel-plate law of its thickness 2 V / A unless a permeability is
// given: a cube of side s inside the box, a = s / 3, k = a² / 12.
TEST(PermeabilityTest, ABodyTakesThePlateLawOfItsThicknessUnlessGivenOne) {
  const TetMesh mesh = Mesh(testing::Cube(6, 14, 0));
  ASSERT_TRUE(mesh.IsBody(0));
  SM_ASSERT_OK_AND_ASSIGN(const PermeabilityResult own, SolvePermeability(mesh, Options()));
  const double a = 8 * kVoxelMm * 1e-3 / 3;
  ASSERT_EQ(own.body_permeability.size(), 1u);
  EXPECT_NEAR(own.body_permeability.at(0), a * a / 12, 1e-9 * a * a / 12);
  EXPECT_GT(own.body_tets, 0u);
  FlowOptions given = Options();
  given.body_permeability = 1e-12;
  SM_ASSERT_OK_AND_ASSIGN(const PermeabilityResult set, SolvePermeability(mesh, given));
  EXPECT_EQ(set.body_permeability.at(0), 1e-12);
  // An inclusion more permeable than the rock raises k, the more so the more permeable.
  EXPECT_GT(own.tensor[0][0], set.tensor[0][0]);
  EXPECT_GT(set.tensor[0][0], kMatrix);
}

TEST(PermeabilityTest, BadInputIsRefusedNamingFieldAndValue) {
  const TetMesh mesh = Mesh(Sheet([](double u, double v) { return Vec3(u, v, 9.5); }, 2, 0));
  FlowOptions o = Options();
  o.matrix_permeability = -1;
  EXPECT_THAT(SolvePermeability(mesh, o), testing::StatusIs(absl::StatusCode::kInvalidArgument,
                                                            HasSubstr("permeability.matrix = -1")));
  o = Options();
  o.body_permeability = 5;
  EXPECT_THAT(SolvePermeability(mesh, o), testing::StatusIs(absl::StatusCode::kInvalidArgument,
                                                            HasSubstr("permeability.body = 5")));
  TetMesh negative = mesh;
  for (size_t f = 0; f < negative.faces.size(); ++f) {
    if (negative.face_piece[f] >= 0) negative.face_thickness_voxels[f] = -1;
  }
  EXPECT_THAT(SolvePermeability(negative, Options()),
              testing::StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("aperture -1")));
  TetMesh unitless = mesh;
  unitless.unit.clear();
  EXPECT_THAT(SolvePermeability(unitless, Options()),
              testing::StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("input.unit")));
  EXPECT_THAT(SolvePermeability(TetMesh{}, Options()),
              testing::StatusIs(absl::StatusCode::kInvalidArgument, HasSubstr("no tetrahedra")));
}

}  // namespace
}  // namespace sheetmesh

namespace sheetmesh {
namespace {

// The image's reference on a voxel slab 2 voxels thick through a 20³ box: the cubic law of
// its 2-voxel aperture along it, the rock in series with it across.
TEST(ImagePermeabilityTest, AVoxelSlabCarriesTheCubicLawAlongIt) {
  const Dims d{20, 20, 20};
  VoxelSet::Builder b(d);
  for (int z = 9; z < 11; ++z) {
    for (int y = 0; y < 20; ++y) b.AddRun(y, z, 0, 20);
  }
  const VoxelSet slab = std::move(b).Build();
  const std::vector<uint16_t> tau(slab.size(), 2);
  const double h = 10e-6;
  FlowOptions o;
  o.matrix_permeability = 1e-18;
  SM_ASSERT_OK_AND_ASSIGN(const ImagePermeability k,
                          SolveImagePermeability(slab, tau, Vec3(h, h, h), o, 1 << 20));
  const double a = 2 * h, l = 20 * h;
  const double along = a * a * a / (12 * l) + o.matrix_permeability * (l - a) / l;
  EXPECT_NEAR(k.tensor[0][0], along, 0.01 * along);
  EXPECT_NEAR(k.tensor[1][1], along, 0.01 * along);
  // Across: the rock's 18 voxels in series with the slab's (nearly free) 2.
  EXPECT_NEAR(k.tensor[2][2], o.matrix_permeability * l / (l - a), 0.01 * o.matrix_permeability);
  EXPECT_EQ(k.cells, 8000u);
  EXPECT_THAT(
      SolveImagePermeability(slab, tau, Vec3(h, h, h), o, 1000),
      testing::StatusIs(absl::StatusCode::kResourceExhausted, ::testing::HasSubstr("8000")));
  EXPECT_THAT(SolveImagePermeability(slab, {}, Vec3(h, h, h), o, 1 << 20),
              testing::StatusIs(absl::StatusCode::kInvalidArgument));
}

}  // namespace
}  // namespace sheetmesh
