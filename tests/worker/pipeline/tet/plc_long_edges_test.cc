// Long sheet edges halved before TetGen (PlcOptions::long_edge_factor).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "tests/testing/status_matchers.h"
#include "worker/pipeline/tet/plc.h"
#include "worker/pipeline/tet/volume_mesher.h"

namespace sheetmesh {
namespace {

constexpr double kPlaneY = 20;

// A sheet in the plane y = 20 across a 40^3 box, as a mid-surface has one: its left half
// (x up to 19.5) a grid of 2-voxel cells, its right half a fan of 20-to-28-voxel
// triangles from the grid's edge to a corner A on the box face x = 39.5, with two more
// reaching the box's corners there (an edge A-B 20 voxels long along the box face).
TriangleMesh FineAndCoarse() {
  TriangleMesh m;
  const int nx = 10, nz = 20;
  auto grid = [&](int i, int k) { return static_cast<uint32_t>(k * (nx + 1) + i); };
  for (int k = 0; k <= nz; ++k) {
    for (int i = 0; i <= nx; ++i) m.vertices.push_back({-0.5 + 2.0 * i, kPlaneY, -0.5 + 2.0 * k});
  }
  for (int k = 0; k < nz; ++k) {
    for (int i = 0; i < nx; ++i) {
      m.faces.push_back({grid(i, k), grid(i + 1, k), grid(i + 1, k + 1)});
      m.faces.push_back({grid(i, k), grid(i + 1, k + 1), grid(i, k + 1)});
    }
  }
  const uint32_t a = static_cast<uint32_t>(m.vertices.size());
  m.vertices.push_back({39.5, kPlaneY, 19.5});  // A
  m.vertices.push_back({39.5, kPlaneY, -0.5});  // B: a corner of the box face's outline
  m.vertices.push_back({39.5, kPlaneY, 39.5});  // C
  for (int k = 0; k < nz; ++k) m.faces.push_back({grid(nx, k), a, grid(nx, k + 1)});
  m.faces.push_back({grid(nx, 0), a + 1, a});
  m.faces.push_back({grid(nx, nz), a, a + 2});
  m.face_piece.assign(m.faces.size(), 0);
  m.face_thickness_voxels.assign(m.faces.size(), 2);
  return m;
}

double Area(const std::vector<Vec3>& v, const Face& f) {
  return 0.5 * Norm(Cross(v[f[1]] - v[f[0]], v[f[2]] - v[f[0]]));
}

TEST(PlcLongEdgesTest, LongSheetEdgesAreHalvedInTheirPlaneAlongTheBoxToo) {
  const TriangleMesh m = FineAndCoarse();
  SM_ASSERT_OK_AND_ASSIGN(const Plc plc, BuildPlc(m, {40, 40, 40}, {}));
  PlcOptions off;
  off.long_edge_factor = 0;
  SM_ASSERT_OK_AND_ASSIGN(const Plc kept, BuildPlc(m, {40, 40, 40}, {}, off));
  EXPECT_EQ(kept.split_long_edges, 0u);
  EXPECT_GT(plc.split_long_edges, 0u);
  EXPECT_GT(plc.sheet_triangles.size(), kept.sheet_triangles.size());
  // No edge over twice the median (2 voxels): the fan's and the box's edges included; the
  // sheet where it was, its area the same.
  double longest = 0, area = 0, area_kept = 0;
  for (const Face& f : plc.sheet_triangles) {
    for (int k = 0; k < 3; ++k) {
      longest = std::max(longest, Norm(plc.vertices[f[(k + 1) % 3]] - plc.vertices[f[k]]));
      EXPECT_DOUBLE_EQ(plc.vertices[f[k]].y, kPlaneY);
    }
    area += Area(plc.vertices, f);
  }
  for (const Face& f : kept.sheet_triangles) area_kept += Area(kept.vertices, f);
  EXPECT_LE(longest, 4.0 + 1e-9);
  EXPECT_NEAR(area, area_kept, 1e-9 * area_kept);
  EXPECT_EQ(plc.sheet_piece.size(), plc.sheet_triangles.size());
  EXPECT_EQ(plc.sheet_thickness.size(), plc.sheet_triangles.size());
  // The sheet's trace on the box face x = 39.5 (A-B and A-C) is that facet's segments, each
  // of at most 4 voxels, through the midpoints.
  std::vector<uint32_t> on_face;
  for (const auto& polygon : plc.facets[1].polygons) {
    if (polygon.size() != 2) continue;
    EXPECT_LE(Norm(plc.vertices[polygon[1]] - plc.vertices[polygon[0]]), 4.0 + 1e-9);
    on_face.insert(on_face.end(), polygon.begin(), polygon.end());
  }
  std::sort(on_face.begin(), on_face.end());
  on_face.erase(std::unique(on_face.begin(), on_face.end()), on_face.end());
  EXPECT_GE(on_face.size(), 17u);  // A, B, C and at least 7 midpoints on each
}

TEST(PlcLongEdgesTest, HalvingLongEdgesLiftsTheVolumeMeshsWorstAngle) {
  const TriangleMesh m = FineAndCoarse();
  VolumeMeshOptions with;
  VolumeMeshOptions without = with;
  without.plc.long_edge_factor = 0;
  SM_ASSERT_OK_AND_ASSIGN(const VolumeMeshResult r, BuildVolumeMesh(m, {40, 40, 40}, {}, with));
  SM_ASSERT_OK_AND_ASSIGN(const VolumeMeshResult o, BuildVolumeMesh(m, {40, 40, 40}, {}, without));
  EXPECT_EQ(r.conformity.conforming, r.conformity.sheet_triangles);
  EXPECT_NEAR(r.quality.volume, r.box_volume, 1e-9 * r.box_volume);
  EXPECT_GE(r.quality.min_dihedral.min, 10.0);
  EXPECT_GT(r.quality.min_dihedral.min, o.quality.min_dihedral.min);
}

}  // namespace
}  // namespace sheetmesh
