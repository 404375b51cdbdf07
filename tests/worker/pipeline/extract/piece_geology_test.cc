#include "worker/pipeline/extract/piece_geology.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/testing/shapes.h"

namespace sheetmesh {
namespace {

TEST(PieceGeologyTest, TiltedSlabHasItsDipApertureAndCentroid) {
  // A slab 4 voxels thick whose normal points up and to +x: dip 30 degrees towards +x (east,
  // dip direction 90).
  const Vec3 n = Normalized(Vec3(std::sin(M_PI / 6), 0, std::cos(M_PI / 6)));
  const VoxelSet s = testing::PlaneSlab({80, 80, 80}, {40, 40, 40}, n, 4);
  LabelledVoxels m{s, std::vector<int32_t>(s.size(), 0)};
  const std::vector<uint16_t> tau(s.size(), 5);  // stand-in τ
  Placement pl;
  pl.spacing = {2, 2, 2};
  TriangleMesh mesh;
  mesh.vertices = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}};
  mesh.faces = {{0, 1, 2}};
  mesh.face_piece = {0};
  const std::vector<PieceGeology> g = ComputePieceGeology(m, tau, mesh, pl);
  ASSERT_EQ(g.size(), 1u);
  EXPECT_NEAR(g[0].dip_degrees, 30.0, 1.0);
  EXPECT_NEAR(g[0].dip_direction_degrees, 90.0, 1.0);
  EXPECT_NEAR(g[0].centroid.x, 80.0, 2.0);  // about voxel 40, at spacing 2
  EXPECT_GT(g[0].planarity, 0.95);
  EXPECT_EQ(g[0].voxels, s.size());
  EXPECT_EQ(g[0].triangles, 1u);
  EXPECT_DOUBLE_EQ(g[0].area, 0.5 * 20 * 20);
  // τ 5 along the axis nearest the normal (z, |n_z| = cos 30) is 5 cos 30 along the normal.
  EXPECT_NEAR(g[0].mean_aperture, 2 * 5 * std::cos(M_PI / 6), 0.05);
  const std::string csv = PieceGeologyCsv(g);
  EXPECT_THAT(csv, ::testing::StartsWith("piece,voxels,triangles,area,mean_aperture"));
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 2);
}

}  // namespace
}  // namespace sheetmesh
