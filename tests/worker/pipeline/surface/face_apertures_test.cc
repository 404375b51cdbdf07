#include "worker/pipeline/surface/face_apertures.h"

#include <gtest/gtest.h>

#include <vector>

namespace sheetmesh {
namespace {

// Two planar sheets crossing along the line x = 4, z = 0: sheet 0 in the plane z = 0
// (x, y in [0, 8]), sheet 1 in the plane x = 4 (y in [0, 8], z in [-4, 4]), two triangles
// per unit square, the vertices on the crossing line shared.
struct Crossing {
  TriangleMesh mesh;
  std::vector<bool> at_junction;  // per face: a vertex on the line
};

Crossing MakeCrossing() {
  Crossing c;
  TriangleMesh& m = c.mesh;
  auto vertex = [&](Vec3 p) {
    for (uint32_t v = 0; v < m.vertices.size(); ++v) {
      if (Norm(m.vertices[v] - p) < 1e-9) return v;
    }
    m.vertices.push_back(p);
    return static_cast<uint32_t>(m.vertices.size() - 1);
  };
  auto grid = [&](int piece, auto at) {
    for (int i = 0; i < 8; ++i) {
      for (int j = 0; j < 8; ++j) {
        const uint32_t a = vertex(at(i, j)), b = vertex(at(i + 1, j)), d = vertex(at(i, j + 1)),
                       e = vertex(at(i + 1, j + 1));
        for (Face f : {Face{a, b, e}, Face{a, e, d}}) {
          m.faces.push_back(f);
          m.face_piece.push_back(piece);
        }
      }
    }
  };
  grid(0, [](int i, int j) { return Vec3{double(i), double(j), 0}; });
  grid(1, [](int i, int j) { return Vec3{4, double(j), double(i) - 4}; });
  for (const Face& f : m.faces) {
    bool on = false;
    for (uint32_t v : f) on |= m.vertices[v].x == 4 && m.vertices[v].z == 0;
    c.at_junction.push_back(on);
  }
  return c;
}

TEST(FaceAperturesTest, AJunctionsFacesCarryTheirOwnSheetsApertureNotTheCrossingsSum) {
  Crossing c = MakeCrossing();
  TriangleMesh& m = c.mesh;
  // Sheet 0 is 2 voxels thick, sheet 1 is 3; the fit gave the junction's faces the sum.
  for (size_t f = 0; f < m.faces.size(); ++f) {
    m.face_thickness_voxels.push_back(c.at_junction[f] ? 5.0f
                                                       : (m.face_piece[f] == 0 ? 2.0f : 3.0f));
  }
  const std::vector<float> measured = m.face_thickness_voxels;
  const FaceApertureStats s = SetFaceApertures(&m, measured);
  ASSERT_EQ(m.face_aperture_voxels.size(), m.faces.size());
  size_t junction = 0;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    EXPECT_FLOAT_EQ(m.face_aperture_voxels[f], m.face_piece[f] == 0 ? 2.0f : 3.0f) << f;
    junction += c.at_junction[f];
  }
  EXPECT_EQ(s.junction, junction);
  EXPECT_EQ(s.junction_lowered, junction);
  EXPECT_EQ(s.junction_raised, 0u);
  // The thickness the score uses stays as fitted.
  for (size_t f = 0; f < m.faces.size(); ++f) {
    EXPECT_FLOAT_EQ(m.face_thickness_voxels[f],
                    c.at_junction[f] ? 5.0f : (m.face_piece[f] == 0 ? 2 : 3));
  }
}

TEST(FaceAperturesTest, ACoveredFaceGetsItsSheetsApertureAndAHoleStaysOpen) {
  Crossing c = MakeCrossing();
  TriangleMesh& m = c.mesh;
  m.face_thickness_voxels.assign(m.faces.size(), 2.0f);
  std::vector<float> measured(m.faces.size(), 2.0f);
  // Two faces of sheet 0 far from the crossing fitted at 0: one over sheet voxels (its
  // neighbours' prisms cover them), one over none (a hole in the sheet).
  const size_t covered = 2, hole = 20;
  ASSERT_FALSE(c.at_junction[covered] || c.at_junction[hole]);
  m.face_thickness_voxels[covered] = m.face_thickness_voxels[hole] = 0;
  measured[hole] = 0;
  // Neighbours of different thickness: the covered face takes the mean of its rings.
  const FaceApertureStats s = SetFaceApertures(&m, measured);
  EXPECT_EQ(s.covered, 1u);
  EXPECT_EQ(s.holes, 1u);
  EXPECT_FLOAT_EQ(m.face_aperture_voxels[covered], 2.0f);
  EXPECT_FLOAT_EQ(m.face_aperture_voxels[hole], 0.0f);
  EXPECT_FLOAT_EQ(m.face_thickness_voxels[covered], 0.0f);
}

TEST(FaceAperturesTest, TheLocalApertureFollowsASheetWhoseThicknessVaries) {
  Crossing c = MakeCrossing();
  TriangleMesh& m = c.mesh;
  // Sheet 0 thickens along x: 1 + x / 2 at the face's first vertex.
  for (size_t f = 0; f < m.faces.size(); ++f) {
    m.face_thickness_voxels.push_back(m.face_piece[f] == 0 ? 1 + m.vertices[m.faces[f][0]].x / 2
                                                           : 3);
  }
  const std::vector<float> measured = m.face_thickness_voxels;
  const size_t far = 2 * (8 * 7 + 3);  // x = 7: 4.5 voxels
  ASSERT_EQ(m.face_piece[far], 0);
  ASSERT_DOUBLE_EQ(m.vertices[m.faces[far][0]].x, 7);
  m.face_thickness_voxels[far] = 0;
  SetFaceApertures(&m, measured);
  EXPECT_GT(m.face_aperture_voxels[far], 3.5f)
      << "the piece's median (3) would ignore where it lies";
  EXPECT_LE(m.face_aperture_voxels[far], 4.5f);
}

}  // namespace
}  // namespace sheetmesh
