#include "worker/pipeline/tet/volume_mesh_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <memory>

#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "common/file_util.h"
#include "common/version.h"
#include "tests/testing/python.h"
#include "tests/testing/status_matchers.h"
#include "tests/testing/temp_dir.h"
#include "tests/worker/pipeline/tet/tet_test_shapes.h"
#include "worker/pipeline/tet/volume_mesher.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::IsOk;
using ::sheetmesh::testing::Python;
using ::sheetmesh::testing::TempDir;

// A box with two sheets (pieces 0 and 3).
TetMesh SampleMesh(const Placement& placement = {}) {
  TriangleMesh sheets;
  for (int s = 0; s < 2; ++s) {
    const double z = s == 0 ? 6 : 13;
    const uint32_t b = static_cast<uint32_t>(sheets.vertices.size());
    sheets.vertices.insert(sheets.vertices.end(), {{4, 4, z}, {15, 4, z}, {15, 15, z}, {4, 15, z}});
    sheets.faces.push_back({b, b + 1, b + 2});
    sheets.faces.push_back({b, b + 2, b + 3});
    sheets.face_piece.insert(sheets.face_piece.end(), {s == 0 ? 0 : 3, s == 0 ? 0 : 3});
    sheets.face_thickness_voxels.insert(sheets.face_thickness_voxels.end(), {2.5f, 2.5f});
  }
  auto r = BuildVolumeMesh(sheets, {20, 20, 20}, placement, {});
  EXPECT_TRUE(r.ok()) << r.status();
  return r->mesh;
}

struct Counts {
  size_t tets = 0, sheet0 = 0, sheet3 = 0, boundary = 0;
};

Counts Expected(const TetMesh& m) {
  Counts c;
  c.tets = m.tets.size();
  for (int32_t p : m.face_piece) {
    c.sheet0 += p == 0;
    c.sheet3 += p == 3;
    c.boundary += p < 0;
  }
  return c;
}

TEST(VolumeMeshIoTest, VtuReadsBackInMeshio) {
  TempDir tmp;
  const TetMesh m = SampleMesh();
  ASSERT_THAT(WriteVtu(tmp.File("m.vtu"), m), IsOk());
  const auto out = Python(
      "import meshio, numpy as np\n"
      "m = meshio.read(\"" +
      tmp.File("m.vtu") +
      "\")\n"
      "piece = np.concatenate(m.cell_data[\"piece\"])\n"
      "kind = np.concatenate(m.cell_data[\"kind\"])\n"
      "print(len(m.points), m.cells_dict[\"tetra\"].shape[0], m.cells_dict[\"triangle\"].shape[0], "
      "int((piece == 0).sum()), int((piece == 3).sum()), int((kind == 2).sum()))");
  if (!out) GTEST_SKIP() << "python3-meshio is not installed for /usr/bin/python3";
  const Counts c = Expected(m);
  EXPECT_EQ(*out, absl::StrCat(m.nodes.size(), " ", c.tets, " ", m.faces.size(), " ", c.sheet0, " ",
                               c.sheet3, " ", c.boundary, "\n"));
}

TEST(VolumeMeshIoTest, GmshReadsBackInMeshioWithPhysicalGroups) {
  TempDir tmp;
  const TetMesh m = SampleMesh();
  ASSERT_THAT(WriteGmsh(tmp.File("m.msh"), m), IsOk());
  const auto out = Python(
      "import meshio, numpy as np\n"
      "m = meshio.read(\"" +
      tmp.File("m.msh") +
      "\")\n"
      "tags = {}\n"
      "for block, phys in zip(m.cells, m.cell_data[\"gmsh:physical\"]):\n"
      "    for t in phys: tags[(block.type, int(t))] = tags.get((block.type, int(t)), 0) + 1\n"
      "names = {k: int(v[0]) for k, v in m.field_data.items()}\n"
      "print(len(m.points), tags.get((\"tetra\", 1), 0), tags.get((\"triangle\", 100), 0), "
      "tags.get((\"triangle\", 103), 0), tags.get((\"triangle\", 2), 0), "
      "names.get(\"rock\"), names.get(\"sheet_3\"), names.get(\"boundary\"))");
  if (!out) GTEST_SKIP() << "python3-meshio is not installed for /usr/bin/python3";
  const Counts c = Expected(m);
  EXPECT_EQ(*out, absl::StrCat(m.nodes.size(), " ", c.tets, " ", c.sheet0, " ", c.sheet3, " ",
                               c.boundary, " 1 103 2\n"));
}

TEST(VolumeMeshIoTest, AbaqusReadsBackInMeshioWithElementSets) {
  TempDir tmp;
  const TetMesh m = SampleMesh();
  ASSERT_THAT(WriteAbaqus(tmp.File("m.inp"), m), IsOk());
  const auto out = Python(
      "import meshio\n"
      "m = meshio.read(\"" +
      tmp.File("m.inp") +
      "\")\n"
      "sizes = {k: sum(len(x) for x in v) for k, v in m.cell_sets.items()}\n"
      "zmin = m.points[m.point_sets[\"BOX_ZMIN\"], 2]\n"
      "print(len(m.points), m.cells_dict[\"tetra\"].shape[0], m.cells_dict[\"triangle\"].shape[0], "
      "sizes.get(\"ROCK\"), sizes.get(\"SHEET_0\"), sizes.get(\"SHEET_3\"), "
      "len(m.point_sets), float(zmin.max() - m.points[:, 2].min()))");
  if (!out) GTEST_SKIP() << "python3-meshio is not installed for /usr/bin/python3";
  const Counts c = Expected(m);
  // The sheets are shells; the box is node sets and a surface, not elements.
  EXPECT_EQ(*out, absl::StrCat(m.nodes.size(), " ", c.tets, " ", c.sheet0 + c.sheet3, " ", c.tets,
                               " ", c.sheet0, " ", c.sheet3, " 6 0.0\n"));
  // The surfaces name a tetrahedron face for every sheet face.
  const std::string inp = *ReadFileToString(tmp.File("m.inp"));
  EXPECT_THAT(inp, ::testing::HasSubstr("*SURFACE, TYPE=ELEMENT, NAME=SURF_SHEET_3"));
  EXPECT_THAT(inp, ::testing::HasSubstr("*SURFACE, TYPE=ELEMENT, NAME=SURF_BOUNDARY"));
  // A section for every element set: CalculiX refuses elements without one.
  EXPECT_THAT(inp, ::testing::HasSubstr("*SOLID SECTION, ELSET=ROCK, MATERIAL=ROCK\n"));
  EXPECT_THAT(inp, ::testing::HasSubstr("*SHELL SECTION, ELSET=SHEET_3, MATERIAL=FRACTURE\n2.5\n"));
}

// Spacing 0.5 x 0.5 x 2: one voxel of thickness is cbrt(0.5) physical, in every array.
TEST(VolumeMeshIoTest, ThicknessIsPhysicalWithAnisotropicSpacing) {
  TempDir tmp;
  Placement pl;
  pl.spacing = {0.5, 0.5, 2.0};
  const TetMesh m = SampleMesh(pl);
  const double t = 2.5 * std::cbrt(0.5);
  for (size_t f = 0; f < m.faces.size(); ++f) {
    EXPECT_NEAR(m.FaceThickness(f), m.face_piece[f] >= 0 ? t : 0.0, 1e-5);
  }
  ASSERT_THAT(WriteVtu(tmp.File("m.vtu"), m), IsOk());
  ASSERT_THAT(WriteGmsh(tmp.File("m.msh"), m), IsOk());
  ASSERT_THAT(WriteAbaqus(tmp.File("m.inp"), m), IsOk());
  const auto out = Python(
      "import meshio, numpy as np\n"
      "m = meshio.read(\"" +
      tmp.File("m.vtu") +
      "\")\n"
      "d = {k: np.concatenate(v) for k, v in m.cell_data.items()}\n"
      "s = d[\"kind\"] == 1\n"
      "print(\"%.4f %.4f %.6f %.6f %d %d\" % (d[\"thickness\"][s].mean(), "
      "d[\"thickness_voxels\"][s].mean(), d[\"permeability\"][s].mean(), "
      "d[\"transmissivity\"][s].mean(), d[\"MaterialIDs\"][s].max(), "
      "d[\"MaterialIDs\"][d[\"kind\"] == 2].min()))");
  if (!out) GTEST_SKIP() << "python3-meshio is not installed for /usr/bin/python3";
  EXPECT_EQ(*out, absl::StrFormat("%.4f 2.5000 %.6f %.6f 4 5\n", t, t * t / 12, t * t * t / 12));
  const std::string msh = *ReadFileToString(tmp.File("m.msh"));
  EXPECT_THAT(msh, ::testing::HasSubstr(absl::StrFormat("$ElementData\n1\n\"thickness\"")));
  EXPECT_THAT(msh, ::testing::HasSubstr(absl::StrFormat(" %.7g\n$EndElementData", t)));
  const std::string inp = *ReadFileToString(tmp.File("m.inp"));
  EXPECT_THAT(inp, ::testing::HasSubstr(absl::StrFormat(
                       "*SHELL SECTION, ELSET=SHEET_0, MATERIAL=FRACTURE\n%.7g\n", t)));
}

}  // namespace
}  // namespace sheetmesh

namespace sheetmesh {
namespace {

// A box with a sheet (piece 0, z = 5) and a body (piece 5: the cube [8, 13]^3, closed and
// outward), meshed: the body's tetrahedra are a region of their own in every writer.
TetMesh MeshWithBody() {
  TriangleMesh m;
  m.vertices = {{3, 3, 5}, {16, 3, 5}, {16, 16, 5}, {3, 16, 5}};
  m.faces = {{0, 1, 2}, {0, 2, 3}};
  m.face_piece = {0, 0};
  m.face_thickness_voxels = {2.f, 2.f};
  m = testing::Append(m, testing::Cube(8, 13, 5));
  m.body_pieces = {5};
  auto r = BuildVolumeMesh(m, {20, 20, 20}, {}, {});
  EXPECT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->bodies.size(), 1u);
  if (!r->bodies.empty()) {
    EXPECT_EQ(r->bodies[0].piece, 5);
    EXPECT_NEAR(r->bodies[0].volume, 125.0, 1e-6);
  }
  return r->mesh;
}

TEST(VolumeMeshIoTest, ABodyIsARegionInEveryWriter) {
  TempDir tmp;
  const TetMesh m = MeshWithBody();
  size_t body_tets = 0, wall_faces = 0;
  for (size_t t = 0; t < m.tets.size(); ++t) body_tets += m.Region(t) == 5;
  for (int32_t p : m.face_piece) wall_faces += p == 5;
  ASSERT_GT(body_tets, 0u);
  ASSERT_THAT(WriteVtu(tmp.File("m.vtu"), m), IsOk());
  ASSERT_THAT(WriteGmsh(tmp.File("m.msh"), m), IsOk());
  ASSERT_THAT(WriteAbaqus(tmp.File("m.inp"), m), IsOk());
  ASSERT_THAT(WriteExodus(tmp.File("m.exo"), m), IsOk());
  const auto vtu = Python(
      "import meshio, numpy as np\n"
      "m = meshio.read(\"" +
      tmp.File("m.vtu") +
      "\")\n"
      "mat = np.concatenate(m.cell_data[\"MaterialIDs\"])\n"
      "kind = np.concatenate(m.cell_data[\"kind\"])\n"
      "print(int(((kind == 0) & (mat == 6)).sum()), int((kind == 3).sum()))");
  if (!vtu) GTEST_SKIP() << "python3-meshio is not installed for /usr/bin/python3";
  EXPECT_EQ(*vtu, absl::StrCat(body_tets, " ", wall_faces, "\n"));
  const auto msh = Python(
      "import meshio\n"
      "m = meshio.read(\"" +
      tmp.File("m.msh") +
      "\")\n"
      "n = sum(len(p) for b, p in zip(m.cells, m.cell_data[\"gmsh:physical\"])"
      " if b.type == \"tetra\" and int(p[0]) == 105)\n"
      "print(n, int(m.field_data[\"body_5\"][0]), int(m.field_data[\"body_5_wall\"][0]))");
  EXPECT_EQ(*msh, absl::StrCat(body_tets, " 105 105\n"));
  const auto inp = Python(
      "import meshio\n"
      "m = meshio.read(\"" +
      tmp.File("m.inp") +
      "\")\n"
      "sizes = {k: sum(len(x) for x in v) for k, v in m.cell_sets.items()}\n"
      "print(sizes.get(\"BODY_5\"), sizes.get(\"ROCK\"), \"SHEET_5\" in sizes)");
  EXPECT_EQ(*inp, absl::StrCat(body_tets, " ", m.tets.size() - body_tets, " False\n"));
  const std::string text = *ReadFileToString(tmp.File("m.inp"));
  EXPECT_THAT(text, ::testing::HasSubstr("*SOLID SECTION, ELSET=BODY_5, MATERIAL=FILL\n"));
  EXPECT_THAT(text, ::testing::HasSubstr("*SURFACE, TYPE=ELEMENT, NAME=SURF_BODY_5\n"));
  // Exodus: blocks rock, body_5 (its tetrahedra) and sheet_0; no block of the body's walls.
  const auto exo = Python(
      "import netCDF4\n"
      "ds = netCDF4.Dataset(\"" +
      tmp.File("m.exo") +
      "\")\n"
      "names = [bytes(n.compressed()).decode() for n in ds.variables[\"eb_names\"][:]]\n"
      "print(\" \".join(names), ds.dimensions[\"num_el_in_blk2\"].size)");
  if (exo && exo->find("Error") == std::string::npos && !exo->empty()) {
    EXPECT_EQ(*exo, absl::StrCat("rock body_5 sheet_0 ", body_tets, "\n"));
  }
}

TEST(VolumeMeshIoTest, EveryFormatStatesItsLengthUnit) {
  // A 5 µm voxel in mm: the nodes are in mm, and each file says so where its format allows.
  Placement placement;
  placement.spacing = {0.005, 0.005, 0.005};
  placement.unit = "mm";
  const TetMesh m = SampleMesh(placement);
  EXPECT_EQ(m.UnitsText(), "lengths in mm (a voxel is 0.005 mm)");
  TempDir tmp;
  ASSERT_THAT(WriteVtu(tmp.File("m.vtu"), m), IsOk());
  ASSERT_THAT(WriteGmsh(tmp.File("m.msh"), m), IsOk());
  ASSERT_THAT(WriteAbaqus(tmp.File("m.inp"), m), IsOk());
  ASSERT_THAT(WriteExodus(tmp.File("m.exo"), m), IsOk());
  EXPECT_THAT(*ReadFileToString(tmp.File("m.vtu")),
              ::testing::HasSubstr("<!-- sheetmesh " SHEETMESH_VERSION
                                   ": lengths in mm (a voxel is 0.005 mm) -->\n<VTKFile"));
  EXPECT_THAT(*ReadFileToString(tmp.File("m.msh")),
              ::testing::HasSubstr("$Comments\nsheetmesh " SHEETMESH_VERSION
                                   ": lengths in mm (a voxel is 0.005 mm)\n$EndComments\n"));
  EXPECT_THAT(*ReadFileToString(tmp.File("m.inp")),
              ::testing::HasSubstr("\n** lengths in mm (a voxel is 0.005 mm)\n*NODE\n"));
  // The files still read as before: the comments are skipped.
  const auto back = Python(
      "import meshio, netCDF4\n"
      "a = meshio.read(\"" +
      tmp.File("m.vtu") +
      "\")\n"
      "b = meshio.read(\"" +
      tmp.File("m.msh") +
      "\")\n"
      "ds = netCDF4.Dataset(\"" +
      tmp.File("m.exo") +
      "\")\n"
      "print(len(a.points) == len(b.points), ds.title)");
  if (!back) GTEST_SKIP() << "python3-meshio is not installed for /usr/bin/python3";
  EXPECT_EQ(*back, "True sheetmesh " SHEETMESH_VERSION
                   " volume mesh, lengths in mm (a voxel is 0.005 mm)\n");
  // Where the volume gives no unit and a voxel is 1, the lengths are voxels.
  EXPECT_EQ(SampleMesh().UnitsText(), "lengths in voxels");
}

}  // namespace
}  // namespace sheetmesh
