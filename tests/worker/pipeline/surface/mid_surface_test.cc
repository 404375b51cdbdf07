#include "worker/pipeline/surface/mid_surface.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "tests/testing/shapes.h"
#include "worker/pipeline/extract/extraction.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/voxel/components.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::ShapeSet;

constexpr double kPi = 3.14159265358979323846;

// Two slabs through the middle of a cube of `n`: a sheet of normal `a` whole, and a sheet
// of normal `b` whole (X) or only on the side of +a (T).
VoxelSet Junction(int n, Vec3 a, Vec3 b, double thickness, bool t_junction) {
  a = Normalized(a);
  b = Normalized(b);
  const Vec3 c(n / 2.0 - 0.5, n / 2.0 - 0.5, n / 2.0 - 0.5);
  return ShapeSet(Dims{n, n, n}, [=](double x, double y, double z) {
    const Vec3 p = Vec3(x, y, z) - c;
    if (std::abs(Dot(p, a)) <= thickness / 2) return true;
    return std::abs(Dot(p, b)) <= thickness / 2 && (!t_junction || Dot(p, a) > 0);
  });
}

// A normal at `degrees` from `a` about the axis `u` (both unit, perpendicular).
Vec3 Turned(Vec3 a, Vec3 u, double degrees) {
  const double r = degrees * kPi / 180;
  return a * std::cos(r) + Cross(u, a) * std::sin(r);
}

double DistanceToLine(const Vec3& p, const Vec3& point, const Vec3& u) {
  const Vec3 w = p - point;
  return Norm(w - u * Dot(w, u));
}

std::vector<int32_t> ComponentLabels(const VoxelSet& set) {
  auto comps = LabelComponents(set, Connectivity::k6);
  EXPECT_TRUE(comps.ok());
  const std::vector<uint32_t> l = comps->VoxelLabels(set);
  return std::vector<int32_t>(l.begin(), l.end());
}

// The pieces the pipeline gives the mid-surface without extraction: the components, those
// that are not height fields as separation cuts them (with its minor pieces and recovery).
std::vector<int32_t> Pieces(const VoxelSet& set) {
  auto pieces =
      MidSurfacePieces(set, ComponentLabels(set), [&]() -> absl::StatusOr<std::vector<int32_t>> {
        ExtractionOptions o;
        o.refine = false;
        o.detect = false;
        auto parts = ExtractFeatures(set, o);
        if (!parts.ok()) return parts.status();
        std::vector<int32_t> out(set.size(), -1);
        parts->model.set.ForEachVoxel([&](uint64_t i, int32_t x, int32_t y, int32_t z) {
          out[set.Find(x, y, z)] = parts->model.label[i];
        });
        return out;
      });
  EXPECT_TRUE(pieces.ok()) << pieces.status();
  return pieces.ok() ? *pieces : std::vector<int32_t>{};
}

TEST(MidSurfaceTest, APlanarSlabIsItsMidPlaneWithItsThicknessAndEndsOnTheBox) {
  const int n = 40;
  const Vec3 normal = Normalized(Vec3(0.3, 0.2, 1.0));
  const Vec3 c(n / 2.0 - 0.5, n / 2.0 - 0.5, n / 2.0 - 0.5);
  const VoxelSet set = ShapeSet(Dims{n, n, n}, [&](double x, double y, double z) {
    return std::abs(Dot(Vec3(x, y, z) - c, normal)) <= 2.0;
  });
  auto mid = BuildMidSurface(set, {});
  ASSERT_TRUE(mid.ok()) << mid.status();
  const TriangleMesh& m = mid->mesh;
  ASSERT_GT(m.faces.size(), 1000u);
  double farthest = 0, thickness = 0;
  for (size_t k = 0; k < m.vertices.size(); ++k) {
    farthest = std::max(farthest, std::abs(Dot(m.vertices[k] - c, normal)));
    thickness += m.vertex_thickness_voxels[k];
    for (int a = 0; a < 3; ++a) {
      const double x = a == 0 ? m.vertices[k].x : a == 1 ? m.vertices[k].y : m.vertices[k].z;
      EXPECT_GE(x, -0.5 - 1e-9);
      EXPECT_LE(x, n - 0.5 + 1e-9);
    }
  }
  EXPECT_LT(farthest, 0.5);
  // The slab is 4 voxels across its normal, up to 5 counted along the z axis.
  EXPECT_NEAR(thickness / m.vertices.size(), 4.0, 0.8);
  EXPECT_TRUE(mid->junctions.empty());
}

// A junction of known angle: the first sheet's normal `a` and the line's direction `u`
// (perpendicular), the second sheet at `degrees` from the first about the line.
struct JunctionCase {
  double degrees;
  bool t_junction;
  Vec3 a, u;
  const char* orientation;
};

// The case's name in the test's: e.g. T30_seed2.
std::string JunctionName(const ::testing::TestParamInfo<JunctionCase>& info) {
  return absl::StrCat(info.param.t_junction ? "T" : "X", static_cast<int>(info.param.degrees), "_",
                      info.param.orientation);
}

// Orientations: the line across the box's axes with the first sheet upright, and two of the
// bench's (bench/junction_sweep.py, seeds 2 and 3), whose sheets stand near a tie between two
// axes (the two halves of one sheet may then be charted along different axes).
const Vec3 kAcross = Normalized(Vec3(0.15, -0.8, 0.55));
const JunctionCase Across(double degrees, bool t) {
  return {degrees, t, Normalized(Cross(kAcross, Vec3(0, 0, 1))), kAcross, "across"};
}
const JunctionCase Seed2(double degrees, bool t) {
  return {degrees, t, Vec3(0.52628, -0.60279, 0.59973), Vec3(-0.81594, -0.15950, 0.55569), "seed2"};
}
const JunctionCase Seed3(double degrees, bool t) {
  return {degrees, t, Vec3(-0.73216, -0.55990, 0.38789), Vec3(0.55526, -0.16078, 0.81599), "seed3"};
}

class JunctionTest : public ::testing::TestWithParam<JunctionCase> {};

TEST_P(JunctionTest, TheSheetsMeetOnTheTrueLineAtTheirAngle) {
  const auto [degrees, t_junction, a_in, u_in, orientation] = GetParam();
  const int n = 64;
  const Vec3 u = Normalized(u_in);
  const Vec3 a = Normalized(a_in - u * Dot(a_in, u));
  const Vec3 b = Turned(a, u, 180 - degrees);
  const VoxelSet set = Junction(n, a, b, 3.0, t_junction);
  const std::vector<int32_t> pieces = Pieces(set);
  auto mid = BuildMidSurface(set, pieces);
  ASSERT_TRUE(mid.ok()) << mid.status();
  ASSERT_EQ(mid->junctions.size(), 1u);
  const JunctionLine& line = mid->junctions[0];
  const Vec3 c(n / 2.0 - 0.5, n / 2.0 - 0.5, n / 2.0 - 0.5);
  EXPECT_GT(std::abs(Dot(line.direction, u)), std::cos(2 * kPi / 180));
  EXPECT_NEAR(line.degrees, std::min(degrees, 180 - degrees), 2.0);
  // Every sample of the line, and every vertex of a face on it, lies within half a voxel of
  // the true line; the pieces: two of each sheet for X, the stem one for T.
  for (uint32_t v : line.vertex_of) {
    if (v == UINT32_MAX) continue;
    EXPECT_LT(DistanceToLine(mid->mesh.vertices[v], c, u), 0.5);
  }
  std::set<int32_t> on_line(line.pieces.begin(), line.pieces.end());
  EXPECT_EQ(on_line.size(), t_junction ? 3u : 4u);
  // The line runs through the box: both its ends are vertices of the mesh on faces of the
  // box, where the sheets meet the face (not a fraction of a voxel inside).
  for (const int k : {0, line.samples() - 1}) {
    ASSERT_NE(line.vertex_of[k], UINT32_MAX) << "end " << k << " is no vertex of the mesh";
    const Vec3& end = mid->mesh.vertices[line.vertex_of[k]];
    double off = 1e300;
    for (int a = 0; a < 3; ++a) {
      const double x = a == 0 ? end.x : a == 1 ? end.y : end.z;
      off = std::min({off, std::abs(x + 0.5), std::abs(x - (n - 0.5))});
    }
    EXPECT_LT(off, 1e-9) << "end " << k << " at " << end.x << " " << end.y << " " << end.z;
  }
}

INSTANTIATE_TEST_SUITE_P(Steep, JunctionTest,
                         ::testing::Values(Across(60, false), Across(60, true), Across(90, false),
                                           Across(90, true), Seed2(60, false), Seed2(90, true),
                                           Seed3(60, true), Seed3(90, false)),
                         JunctionName);
INSTANTIATE_TEST_SUITE_P(Shallow, JunctionTest,
                         ::testing::Values(Across(30, true), Across(30, false), Seed2(30, true),
                                           Seed3(30, true), Seed3(30, false)),
                         JunctionName);
// Not yet within the aim in this 64^3 box (bench/RESULTS.md, issue 64): at 15 degrees the
// line's samples lie up to 0.55 (X) and 0.8 voxels (T) off the true line, or (the X of
// seed 2) the crossing gives two lines where there is one; the X at 30 degrees of seed 2
// gives two.
INSTANTIATE_TEST_SUITE_P(DISABLED_Shallow, JunctionTest,
                         ::testing::Values(Across(15, false), Across(15, true), Seed2(30, false),
                                           Seed3(15, false), Seed2(15, true), Seed2(15, false)),
                         JunctionName);

// A junction that ends inside the box: a strip of a second sheet, 24 voxels wide along the
// line, crossing a whole one. Beyond the line's ends the charts are not zipped to it: no fan
// of long triangles from a line's end over a chart's own columns, no edge that one piece's
// faces fold over (three or more of them on it), and no piece that lost its voxels.
TEST(MidSurfaceTest, AJunctionEndingInsideTheBoxFoldsNoChartOverItself) {
  const int n = 64;
  const Vec3 u = Normalized(Vec3(0.15, -0.8, 0.55));
  const Vec3 a = Normalized(Cross(u, Vec3(0, 0, 1)));
  const Vec3 b = Turned(a, u, 180 - 60);
  const Vec3 c(n / 2.0 - 0.5, n / 2.0 - 0.5, n / 2.0 - 0.5);
  const VoxelSet set = ShapeSet(Dims{n, n, n}, [=](double x, double y, double z) {
    const Vec3 p = Vec3(x, y, z) - c;
    if (std::abs(Dot(p, a)) <= 1.5) return true;
    return std::abs(Dot(p, b)) <= 1.5 && std::abs(Dot(p, u)) <= 12;
  });
  const std::vector<int32_t> pieces = Pieces(set);
  auto mid = BuildMidSurface(set, pieces);
  ASSERT_TRUE(mid.ok()) << mid.status();
  const TriangleMesh& m = mid->mesh;
  ASSERT_FALSE(mid->junctions.empty());
  std::map<std::pair<uint32_t, uint32_t>, std::map<int32_t, int>> faces_of_edge;
  double longest = 0;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t p = m.faces[f][k], q = m.faces[f][(k + 1) % 3];
      ++faces_of_edge[{std::min(p, q), std::max(p, q)}][m.face_piece[f]];
      longest = std::max(longest, Norm(m.vertices[p] - m.vertices[q]));
    }
  }
  int folded = 0;
  for (const auto& [edge, by_piece] : faces_of_edge) {
    for (const auto& [piece, count] : by_piece) folded += count > 2;
  }
  EXPECT_EQ(folded, 0);
  EXPECT_LT(longest, 8.0);
  // Both sheets keep their area: the whole one about n^2 (it stands across x), the strip
  // about 24 n more.
  double area = 0;
  for (size_t f = 0; f < m.faces.size(); ++f) area += Area(Corners(m, f));
  EXPECT_GT(area, 1.2 * n * n);
  EXPECT_LT(area, 1.6 * n * n);
}

TEST(MidSurfaceTest, SheetsEndingInsideTheBoxEndTheirJunctionWhereTheyEnd) {
  // Two 4-voxel slabs crossing at right angles, both ending 10 voxels inside the box (y in
  // [10, 53]): the junction line and every triangle stop where the sheets do. A line run on
  // to the box left flaps with no aperture reaching the faces y = -0.5 and y = 63.5 (the
  // planar junction phantom at r = 5: 25 triangles beyond its slabs).
  const int n = 64;
  const VoxelSet set = ShapeSet(Dims{n, n, n}, [=](double x, double y, double z) {
    if (y < 10 || y > 53 || x < 10 || x > 53 || z < 10 || z > 53) return false;
    return (z >= 30 && z <= 33) || (x >= 30 && x <= 33);
  });
  auto mid = BuildMidSurface(set, Pieces(set));
  ASSERT_TRUE(mid.ok()) << mid.status();
  ASSERT_FALSE(mid->junctions.empty());
  double lo = n, hi = -1;
  for (const Vec3& p : mid->mesh.vertices) {
    lo = std::min(lo, p.y);
    hi = std::max(hi, p.y);
  }
  EXPECT_GT(lo, 10 - 3.5);
  EXPECT_LT(hi, 53 + 3.5);
}

TEST(MidSurfaceTest, ATJunctionEndingAtACrossingCutsNoSheetBeyondItsEnd) {
  // The planar junction phantom at half size: slabs x and z (4 voxels) cross along y, both
  // ending 6 voxels inside the box, and a slab y stands on both in the quadrant x, z > 33
  // only, meeting each in a T that ends at the crossing. The half of slab z at x < 30 meets
  // the T's line only at its end: it stays one sheet, and no chart lies over another (the
  // T's line cut it along its whole length, and the part beyond, joined to the other
  // half's, overlapped its neighbours: 40 clashing face pairs at r = 5 on the phantom, 238
  // at r = 3).
  const int n = 96;
  const VoxelSet set = ShapeSet(Dims{n, n, n}, [=](double x, double y, double z) {
    const bool x_slab = x >= 46 && x <= 49 && y >= 8 && y <= 87 && z >= 8 && z <= 87;
    const bool z_slab = z >= 46 && z <= 49 && y >= 8 && y <= 87 && x >= 8 && x <= 87;
    const bool y_slab = y >= 22 && y <= 25 && x > 49 && x <= 87 && z > 49 && z <= 87;
    return x_slab || z_slab || y_slab;
  });
  auto mid = BuildMidSurface(set, Pieces(set));
  ASSERT_TRUE(mid.ok()) << mid.status();
  const TriangleMesh& m = mid->mesh;
  EXPECT_GE(mid->junctions.size(), 3u);
  // No chart lies over another's (a fold of one chart at a line's end is left: issue 64).
  int between_pieces = 0;
  for (const auto& [f, g] : FindSelfIntersections(m, 1000)) {
    between_pieces += m.face_piece[f] != m.face_piece[g];
  }
  EXPECT_EQ(between_pieces, 0);
  std::set<int32_t> pieces_of_the_half;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const Vec3 c =
        (m.vertices[m.faces[f][0]] + m.vertices[m.faces[f][1]] + m.vertices[m.faces[f][2]]) / 3.0;
    if (std::abs(c.z - 47.5) < 1 && c.x < 42) pieces_of_the_half.insert(m.face_piece[f]);
  }
  EXPECT_EQ(pieces_of_the_half.size(), 1u);
}

TEST(MidSurfacePiecesTest, AFlatSheetStaysWholeAndASteepCrossingAsksSeparation) {
  const int n = 48;
  const Vec3 u = Normalized(Vec3(0.1, -0.7, 0.7));
  const Vec3 a = Normalized(Cross(u, Vec3(1, 0, 0)));
  {
    const VoxelSet flat = Junction(n, a, a, 3.0, false);
    int calls = 0;
    auto pieces = MidSurfacePieces(flat, ComponentLabels(flat), [&] {
      ++calls;
      return absl::StatusOr<std::vector<int32_t>>(std::vector<int32_t>(flat.size(), 0));
    });
    ASSERT_TRUE(pieces.ok());
    EXPECT_EQ(calls, 0);
    EXPECT_EQ(*pieces, ComponentLabels(flat));
  }
  {
    // A T at 90 degrees: no axis sees both sheets as height fields.
    const VoxelSet t = Junction(n, a, Turned(a, u, 90), 3.0, true);
    int calls = 0;
    auto pieces = MidSurfacePieces(t, ComponentLabels(t), [&] {
      ++calls;
      std::vector<int32_t> s(t.size(), 7);
      s[0] = -1;
      return absl::StatusOr<std::vector<int32_t>>(s);
    });
    ASSERT_TRUE(pieces.ok());
    EXPECT_EQ(calls, 1);
    EXPECT_EQ((*pieces)[0], -1);
    EXPECT_EQ((*pieces)[1], 1 + 7);  // past the one component's label
  }
  {
    const VoxelSet t = Junction(n, a, Turned(a, u, 90), 3.0, true);
    auto pieces = MidSurfacePieces(t, ComponentLabels(t), [] {
      return absl::StatusOr<std::vector<int32_t>>(absl::CancelledError("asked"));
    });
    EXPECT_EQ(pieces.status().code(), absl::StatusCode::kCancelled);
  }
}

TEST(SettleAtBoxTest, TheRimLiesOnTheFaceAndTheVerticesNearItSlideAlongTheSheet) {
  // A strip of the plane z = x - 0.5 tan-ed at 45 degrees to the face x = -0.5: rim
  // vertices a hair off the face, the next row 0.05 voxel inside it.
  TriangleMesh m;
  const double s = 2.0;
  for (int row = 0; row < 4; ++row) {
    for (int k = 0; k < 5; ++k) {
      double x = -0.5 + row * s;
      if (row == 0) x += 0.03;
      if (row == 1) x = -0.45;
      m.vertices.push_back(Vec3(x, k * s, 10 + x));
      m.vertex_thickness_voxels.push_back(2);
    }
  }
  for (int row = 0; row + 1 < 4; ++row) {
    for (int k = 0; k + 1 < 5; ++k) {
      const uint32_t v = row * 5 + k;
      m.faces.push_back({v, v + 5, v + 1});
      m.faces.push_back({v + 1, v + 5, v + 6});
    }
  }
  m.face_piece.assign(m.faces.size(), 0);
  const std::vector<Face> faces = m.faces;
  EXPECT_GT(SettleAtBox(Dims{20, 20, 20}, &m), 0u);
  for (int k = 0; k < 5; ++k) EXPECT_DOUBLE_EQ(m.vertices[k].x, -0.5) << k;
  for (int k = 1; k < 4; ++k) {
    const Vec3& p = m.vertices[5 + k];
    EXPECT_GE(p.x, -0.5 + 0.99) << k;  // a voxel off the face
    EXPECT_NEAR(p.z - p.x, 10, 1e-9);  // still on the sheet's plane
  }
  EXPECT_EQ(m.faces, faces);
}

}  // namespace
}  // namespace sheetmesh
