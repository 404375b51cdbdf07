#include "worker/pipeline/scvd/dual_triangles.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/testing/status_matchers.h"

namespace sheetmesh {
namespace {

// A hand-made diagram over one 2x2x2 block of voxels with the given cells, generator
// positions and adjacency.
struct Fixture {
  VoxelSet set;
  NeighborTable neighbors;
  Scvd scvd;
  std::vector<uint16_t> thickness;
};

Fixture Make(const std::vector<uint32_t>& cells_zyx, std::vector<Vec3> generators,
             std::vector<std::pair<uint32_t, uint32_t>> adjacency) {
  Fixture f;
  std::vector<Index3> idx;
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 2; ++x) idx.push_back({x, y, z});
  f.set = VoxelSet::FromIndices({2, 2, 2}, idx);
  f.neighbors = *NeighborTable::Build(f.set);
  f.scvd.cell = cells_zyx;
  f.scvd.adjacency = adjacency;
  for (size_t g = 0; g < generators.size(); ++g) {
    f.scvd.generators.push_back({static_cast<int32_t>(generators[g].x), 0, 0});
    f.scvd.generator_voxel.push_back(0);
    f.scvd.generator_component.push_back(0);
  }
  f.thickness.assign(8, 1);
  return f;
}

std::vector<Face> Sorted(std::vector<Face> faces) {
  for (Face& f : faces) std::sort(f.begin(), f.end());
  std::sort(faces.begin(), faces.end());
  return faces;
}

TEST(DualTrianglesTest, ThreeCellsInABlockGiveOneTriangle) {
  Fixture f =
      Make({0, 0, 1, 1, 2, 2, 2, 2}, {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}}, {{0, 1}, {0, 2}, {1, 2}});
  const std::vector<Vec3> pos = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}};
  DualTriangleOptions o;
  o.rim = false;
  SM_ASSERT_OK_AND_ASSIGN(DualTriangulation t,
                          TriangulateScvd(f.set, f.neighbors, f.thickness, f.scvd, pos, o));
  EXPECT_THAT(Sorted(t.faces), ::testing::ElementsAre(Face{0, 1, 2}));
  EXPECT_GE(t.stats.blocks_three, 1u);
}

TEST(DualTrianglesTest, AmendingSplitsTheQuadAlongItsShorterDiagonal) {
  // Fig. 9: cells A=0, B=1, C=2, D=3 meet in one block; the fronts met as B-D, C-D, A-C,
  // A-B, so the polygon is A B D C. A and D are close, B and C far apart: the diagonal is AD.
  Fixture f = Make({0, 1, 2, 3, 0, 1, 2, 3}, {{}, {}, {}, {}}, {{1, 3}, {2, 3}, {0, 2}, {0, 1}});
  const std::vector<Vec3> pos = {{0, 0, 0}, {6, -4, 0}, {-6, 4, 0}, {2, 1, 0}};
  DualTriangleOptions o;
  o.rim = false;
  SM_ASSERT_OK_AND_ASSIGN(DualTriangulation t,
                          TriangulateScvd(f.set, f.neighbors, f.thickness, f.scvd, pos, o));
  EXPECT_THAT(Sorted(t.faces), ::testing::ElementsAre(Face{0, 1, 3}, Face{0, 2, 3}));
  EXPECT_GE(t.stats.blocks_amended, 1u);
  // With D moved far away, the other diagonal (BC) is the shorter one.
  const std::vector<Vec3> pos2 = {{0, -1.5, 0}, {3, -1, 0}, {-3, 1, 0}, {1, 9, 0}};
  SM_ASSERT_OK_AND_ASSIGN(t, TriangulateScvd(f.set, f.neighbors, f.thickness, f.scvd, pos2, o));
  EXPECT_THAT(Sorted(t.faces), ::testing::ElementsAre(Face{0, 1, 2}, Face{1, 2, 3}));
}

TEST(DualTrianglesTest, CellsWithoutAPolygonGiveTheirAdjacencyTriangles) {
  // D touches only C: no cycle through all four; ABC is a clique.
  Fixture f = Make({0, 1, 2, 3, 0, 1, 2, 3}, {{}, {}, {}, {}}, {{0, 1}, {1, 2}, {0, 2}, {2, 3}});
  const std::vector<Vec3> pos = {{0, 0, 0}, {5, 0, 0}, {0, 5, 0}, {-3, 7, 1}};
  DualTriangleOptions o;
  o.rim = false;
  SM_ASSERT_OK_AND_ASSIGN(DualTriangulation t,
                          TriangulateScvd(f.set, f.neighbors, f.thickness, f.scvd, pos, o));
  EXPECT_THAT(Sorted(t.faces), ::testing::ElementsAre(Face{0, 1, 2}));
}

TEST(DualTrianglesTest, PositionsMustMatchGenerators) {
  Fixture f = Make({0, 0, 1, 1, 2, 2, 2, 2}, {{}, {}, {}}, {});
  const std::vector<Vec3> pos = {{0, 0, 0}};
  EXPECT_THAT(TriangulateScvd(f.set, f.neighbors, f.thickness, f.scvd, pos),
              testing::StatusIs(absl::StatusCode::kInvalidArgument));
}

}  // namespace
}  // namespace sheetmesh
