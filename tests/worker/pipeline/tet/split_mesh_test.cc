// Splitting the volume mesh along its sheets, on real TetGen meshes: a crack inside the box
// keeps its rim, a sheet through the box parts it, crossing sheets give four sides on their
// common line; the interfaces face the way the sheets do; the Abaqus, CalculiX and Exodus
// decks carry the two sides, and CalculiX opens the crack under tension.
#include "worker/pipeline/tet/split_mesh.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "common/file_util.h"
#include "tests/testing/python.h"
#include "tests/testing/status_matchers.h"
#include "tests/testing/temp_dir.h"
#include "tests/worker/pipeline/tet/tet_test_shapes.h"
#include "worker/pipeline/tet/volume_mesh_io.h"
#include "worker/pipeline/tet/volume_mesher.h"

namespace sheetmesh {
namespace {

using ::sheetmesh::testing::IsOk;
using ::sheetmesh::testing::Python;
using ::sheetmesh::testing::TempDir;
using ::testing::HasSubstr;

constexpr int kSide = 20;

TetMesh Mesh(const TriangleMesh& sheets) {
  auto r = BuildVolumeMesh(sheets, {kSide, kSide, kSide}, {}, {});
  EXPECT_TRUE(r.ok()) << r.status();
  return r->mesh;
}

// A crack inside the box: a square of side 10 at z = 9.5, its rim 5 voxels from every side.
TetMesh Crack() { return Mesh(testing::Square(4.5, 14.5, 9.5, 4)); }

// A sheet through the whole box at z = 9.5.
TetMesh Through() { return Mesh(testing::Square(-0.5, kSide - 0.5, 9.5, 4)); }

SplitMesh Split(const TetMesh& m) {
  auto s = SplitAlongSheets(m);
  EXPECT_THAT(s.status(), IsOk());
  return *std::move(s);
}

// The nodes of the sheet faces, and those on the sheets' rim (on an edge only one sheet face
// has).
struct SheetNodes {
  std::set<uint32_t> all, rim;
};
SheetNodes NodesOf(const TetMesh& m) {
  SheetNodes out;
  std::map<std::pair<uint32_t, uint32_t>, int> edges;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (m.face_piece[f] < 0) continue;
    const auto& q = m.faces[f];
    for (int i = 0; i < 3; ++i) {
      out.all.insert(q[i]);
      const uint32_t a = std::min(q[i], q[(i + 1) % 3]), b = std::max(q[i], q[(i + 1) % 3]);
      ++edges[{a, b}];
    }
  }
  for (const auto& [e, n] : edges) {
    if (n == 1) out.rim.insert({e.first, e.second});
  }
  return out;
}

TEST(SplitMeshTest, APieceOfRockTooSmallToHoldStaysGluedSoNothingFloats) {
  // The sheet through the box, and one tetrahedron on it whose other three faces are made
  // sheet faces too: sheets crossing close together enclose such a sliver of rock, which
  // split free would float, held by contact alone (a static solve has no answer).
  TetMesh m = Through();
  std::optional<size_t> lone;
  std::set<std::array<uint32_t, 3>> on_sheet;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (m.face_piece[f] < 0) continue;
    std::array<uint32_t, 3> q = m.faces[f];
    std::sort(q.begin(), q.end());
    on_sheet.insert(q);
  }
  for (size_t t = 0; t < m.tets.size() && !lone; ++t) {
    for (int k = 0; k < 4 && !lone; ++k) {
      std::array<uint32_t, 3> q;
      for (int i = 0, j = 0; i < 4; ++i)
        if (i != k) q[j++] = m.tets[t][i];
      std::sort(q.begin(), q.end());
      if (!on_sheet.contains(q)) continue;
      lone = t;
      for (int other = 0; other < 4; ++other) {
        if (other == k) continue;
        std::array<uint32_t, 3> g;
        for (int i = 0, j = 0; i < 4; ++i)
          if (i != other) g[j++] = m.tets[t][i];
        m.faces.push_back(g);
        m.face_piece.push_back(0);
        m.face_thickness_voxels.push_back(1);
      }
    }
  }
  ASSERT_TRUE(lone.has_value());
  const SplitMesh s = Split(m);
  EXPECT_EQ(s.stats.glued_regions, 1u);
  // Every piece of the split mesh (tetrahedra sharing nodes) has 8 tetrahedra or more.
  std::vector<uint32_t> up(s.mesh.nodes.size());
  std::iota(up.begin(), up.end(), 0u);
  auto find = [&](uint32_t i) {
    while (up[i] != i) i = up[i] = up[up[i]];
    return i;
  };
  for (const Tet& t : s.mesh.tets)
    for (int k = 1; k < 4; ++k) up[find(t[k])] = find(t[0]);
  std::map<uint32_t, size_t> tets_of;
  for (const Tet& t : s.mesh.tets) ++tets_of[find(t[0])];
  for (const auto& [root, n] : tets_of) EXPECT_GE(n, 8u) << "a piece of " << n << " floats";
  // The sliver bonds the sheets round it where it sits, the through sheet too: one piece
  // (without it, the two halves and the sliver).
  EXPECT_EQ(tets_of.size(), 1u);
}

TEST(SplitMeshTest, ACrackInsideTheBoxCopiesEveryNodeButItsRims) {
  const TetMesh m = Crack();
  const SplitMesh s = Split(m);
  const SheetNodes n = NodesOf(m);
  ASSERT_GT(n.rim.size(), 0u);
  EXPECT_EQ(s.stats.sheet_nodes, n.all.size());
  EXPECT_EQ(s.stats.rim_nodes, n.rim.size());
  EXPECT_EQ(s.stats.added_nodes, n.all.size() - n.rim.size());
  EXPECT_EQ(s.mesh.nodes.size(), m.nodes.size() + n.all.size() - n.rim.size());
  // Every copy is of an interior sheet node, once; a rim node is never copied.
  std::map<uint32_t, int> copies;
  for (size_t v = m.nodes.size(); v < s.mesh.nodes.size(); ++v) ++copies[s.parent[v]];
  for (const auto& [v, k] : copies) {
    EXPECT_TRUE(n.all.count(v) && !n.rim.count(v)) << v;
    EXPECT_EQ(k, 1) << v;
  }
  EXPECT_EQ(s.interfaces.size(), m.num_sheet_faces());
  EXPECT_EQ(s.stats.unsplit_faces, 0u);
}

TEST(SplitMeshTest, InterfacesFaceTheWayTheSheetFacesDo) {
  const TetMesh m = Crack();
  const SplitMesh s = Split(m);
  size_t open = 0;
  for (const SheetInterface& in : s.interfaces) {
    const auto& q = m.faces[in.face];
    const Vec3 n = Cross(m.nodes[q[1]] - m.nodes[q[0]], m.nodes[q[2]] - m.nodes[q[0]]);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(s.parent[in.neg[i]], q[i]);
      EXPECT_EQ(s.parent[in.pos[i]], q[i]);
    }
    // The bottom (neg) triangle's normal by the right-hand rule is the face's, and points to
    // the pos tetrahedron: its centroid lies on the positive side, the neg one's on the other.
    const auto& p = s.mesh.nodes;
    const Vec3 bottom = Cross(p[in.neg[1]] - p[in.neg[0]], p[in.neg[2]] - p[in.neg[0]]);
    EXPECT_GT(Dot(bottom, n), 0);
    const auto centroid = [&](uint32_t t) {
      const Tet& k = s.mesh.tets[t];
      return (p[k[0]] + p[k[1]] + p[k[2]] + p[k[3]]) / 4.0;
    };
    EXPECT_LT(Dot(n, centroid(in.tet_neg) - p[in.neg[0]]), 0);
    EXPECT_GT(Dot(n, centroid(in.tet_pos) - p[in.neg[0]]), 0);
    open += !in.Closed();
  }
  EXPECT_EQ(open + s.stats.closed_faces, s.interfaces.size());
  EXPECT_GT(open, s.interfaces.size() / 2);
  // The tetrahedra keep their shape and orientation on the copies.
  for (size_t t = 0; t < m.tets.size(); ++t) {
    for (int k = 0; k < 4; ++k) EXPECT_EQ(s.parent[s.mesh.tets[t][k]], m.tets[t][k]);
  }
}

TEST(SplitMeshTest, ASheetThroughTheBoxPartsItEverywhere) {
  const TetMesh m = Through();
  const SplitMesh s = Split(m);
  // No rim inside the rock: every sheet node, on the box's sides too, gets a copy.
  EXPECT_EQ(s.stats.rim_nodes, 0u);
  EXPECT_EQ(s.stats.added_nodes, s.stats.sheet_nodes);
  EXPECT_EQ(s.stats.closed_faces, 0u);
  // The tetrahedra fall into two parts that share no node.
  std::set<uint32_t> below, above;
  for (const Tet& t : s.mesh.tets) {
    Vec3 c;
    for (uint32_t v : t) c = c + s.mesh.nodes[v] / 4.0;
    (c.z < 9.5 ? below : above).insert(t.begin(), t.end());
  }
  for (uint32_t v : below) EXPECT_EQ(above.count(v), 0u) << v;
}

TEST(SplitMeshTest, CrossingSheetsGiveFourSidesOnTheirCommonLine) {
  const TetMesh m = Mesh(testing::Append(testing::Square(-0.5, kSide - 0.5, 9.5, 4, 0),
                                         testing::Square(-0.5, kSide - 0.5, 9.5, 4, 1, 3, 0)));
  const SplitMesh s = Split(m);
  std::map<uint32_t, int> copies;
  for (size_t v = m.nodes.size(); v < s.mesh.nodes.size(); ++v) ++copies[s.parent[v]];
  size_t on_line = 0;
  for (uint32_t v = 0; v < m.nodes.size(); ++v) {
    const Vec3& p = m.nodes[v];
    if (std::abs(p.x - 9.5) < 1e-9 && std::abs(p.z - 9.5) < 1e-9) {
      ++on_line;
      EXPECT_EQ(copies[v], 3) << "node " << v << " at y " << p.y;  // four sides: three copies
    }
  }
  EXPECT_GT(on_line, 2u);
  EXPECT_EQ(s.stats.rim_nodes, 0u);
}

TEST(SplitMeshTest, AMeshWithoutSheetsSplitsToItselfAndItsDecksAreWritten) {
  const TetMesh m = Mesh(TriangleMesh{});
  const SplitMesh s = Split(m);
  EXPECT_EQ(s.stats.sheet_nodes, 0u);
  EXPECT_EQ(s.stats.added_nodes, 0u);
  EXPECT_TRUE(s.interfaces.empty());
  EXPECT_EQ(s.mesh.nodes.size(), m.nodes.size());
  TempDir tmp;
  EXPECT_THAT(WriteSplitAbaqus(tmp.File("a.inp"), s, false), IsOk());
  EXPECT_THAT(WriteSplitAbaqus(tmp.File("c.inp"), s, true), IsOk());
  EXPECT_THAT(WriteSplitExodus(tmp.File("s.exo"), s), IsOk());
  EXPECT_THAT(*ReadFileToString(tmp.File("c.inp")), ::testing::Not(HasSubstr("*CONTACT PAIR")));
}

TEST(SplitMeshTest, TheAbaqusDeckHasACohesiveElementPerOpenFace) {
  TempDir tmp;
  const SplitMesh s = Split(Crack());
  ASSERT_THAT(WriteSplitAbaqus(tmp.File("a.inp"), s, false), IsOk());
  const std::string inp = *ReadFileToString(tmp.File("a.inp"));
  const size_t at = inp.find("*ELEMENT, TYPE=COH3D6, ELSET=SHEET_0\n");
  ASSERT_NE(at, std::string::npos);
  // Each line: id, the neg side's three nodes, then the pos side's, in the face's order.
  std::map<std::array<uint32_t, 3>, std::array<uint32_t, 3>> written;
  std::istringstream lines(inp.substr(at + 37));
  for (std::string line; std::getline(lines, line) && line[0] != '*';) {
    const std::vector<std::string> v = absl::StrSplit(line, ", ");
    ASSERT_EQ(v.size(), 7u) << line;
    std::array<uint32_t, 3> neg, pos;
    for (int i = 0; i < 3; ++i) {
      neg[i] = std::stoul(v[1 + i]) - 1;
      pos[i] = std::stoul(v[4 + i]) - 1;
    }
    written[neg] = pos;
  }
  EXPECT_EQ(written.size(), s.interfaces.size() - s.stats.closed_faces);
  for (const SheetInterface& in : s.interfaces) {
    if (in.Closed()) continue;
    ASSERT_TRUE(written.count(in.neg));
    EXPECT_EQ(written[in.neg], in.pos);
  }
  EXPECT_THAT(inp, HasSubstr("*COHESIVE SECTION, ELSET=SHEET_0, MATERIAL=FRACTURE, RESPONSE="
                             "TRACTION SEPARATION, THICKNESS=SPECIFIED\n1.\n"));
  EXPECT_THAT(inp, HasSubstr("*ELASTIC, TYPE=TRACTION\n"));
  EXPECT_THAT(inp, HasSubstr("*SURFACE, TYPE=ELEMENT, NAME=SURF_SHEET_0_NEG\n"));
  EXPECT_THAT(inp, HasSubstr("*SURFACE, TYPE=ELEMENT, NAME=SURF_SHEET_0_POS\n"));
  EXPECT_THAT(inp, ::testing::Not(HasSubstr("TYPE=S3")));
}

TEST(SplitMeshTest, TheExodusFileHasBothSidesAsSideSets) {
  TempDir tmp;
  const SplitMesh s = Split(Crack());
  ASSERT_THAT(WriteSplitExodus(tmp.File("s.exo"), s), IsOk());
  const auto out = Python(
      "import netCDF4\n"
      "d = netCDF4.Dataset(\"" +
          tmp.File("s.exo") +
          "\")\n"
          "names = [bytes(n.compressed()).decode() for n in d.variables[\"ss_names\"][:]]\n"
          "ids = list(d.variables[\"ss_prop1\"][:])\n"
          "k = names.index(\"sheet_0_neg\") + 1\n"
          "print(len(names), names[k - 1], names[k], ids[k - 1], ids[k], "
          "len(d.variables[\"elem_ss%d\" % k][:]), len(d.variables[\"elem_ss%d\" % (k + 1)][:]), "
          "d.dimensions[\"num_nodes\"].size)",
      "netCDF4");
  if (!out) GTEST_SKIP() << "python3-netcdf4 is not installed for /usr/bin/python3";
  const size_t n = s.interfaces.size();
  EXPECT_EQ(*out, absl::StrCat("8 sheet_0_neg sheet_0_pos 1000 1001 ", n, " ", n, " ",
                               s.mesh.nodes.size(), "\n"));
}

// Reads the displacements CalculiX printed for the node set `set` from its .dat file.
std::map<uint32_t, Vec3> PrintedDisplacements(const std::string& dat, const std::string& set) {
  std::map<uint32_t, Vec3> out;
  const size_t at = dat.find(absl::StrCat("displacements (vx,vy,vz) for set ", set));
  if (at == std::string::npos) return out;
  std::istringstream lines(dat.substr(dat.find('\n', at) + 1));
  std::string line;
  std::getline(lines, line);  // blank
  while (std::getline(lines, line)) {
    std::istringstream f(line);
    uint32_t id;
    Vec3 u;
    if (!(f >> id >> u.x >> u.y >> u.z)) break;
    out[id - 1] = u;
  }
  return out;
}

// The crack's opening in CalculiX with the bottom clamped and the top moved up by `lift`:
// at each interface vertex the pos copy's rise over the neg copy's; the one nearest the
// middle, the least and the most. nullopt where ccx is not installed.
struct Opening {
  double centre = 0, least = 1e300, most = -1e300;
};
std::optional<Opening> CrackOpening(const SplitMesh& s, double lift) {
  if (std::system("command -v ccx >/dev/null 2>&1") != 0) return std::nullopt;
  TempDir tmp;
  EXPECT_THAT(WriteSplitAbaqus(tmp.File("split.inp"), s, true), IsOk());
  std::ofstream(tmp.File("job.inp")) << "*INCLUDE, INPUT=split.inp\n"
                                        "*STEP\n*STATIC\n*BOUNDARY\nBOX_ZMIN, 1, 3, 0.\n"
                                        "BOX_ZMAX, 3, 3, "
                                     << lift
                                     << "\n*NODE PRINT, NSET=SHEET_0_NEG\nU\n"
                                        "*NODE PRINT, NSET=SHEET_0_POS\nU\n*END STEP\n";
  const std::string run =
      absl::StrCat("cd ", tmp.path(), " && OMP_NUM_THREADS=2 ccx job > ccx.log 2>&1");
  const int rc = std::system(run.c_str());
  const std::string log = ReadFileToString(tmp.File("ccx.log")).value_or("");
  EXPECT_EQ(rc, 0) << log.substr(log.size() > 3000 ? log.size() - 3000 : 0);
  EXPECT_THAT(log, HasSubstr("Job finished"));
  const std::string dat = ReadFileToString(tmp.File("job.dat")).value_or("");
  const auto neg = PrintedDisplacements(dat, "SHEET_0_NEG");
  const auto pos = PrintedDisplacements(dat, "SHEET_0_POS");
  Opening o;
  double nearest = 1e300;
  for (const SheetInterface& in : s.interfaces) {
    for (int i = 0; i < 3; ++i) {
      if (!neg.count(in.neg[i]) || !pos.count(in.pos[i])) {
        ADD_FAILURE() << "no displacement printed for node " << in.neg[i] << " or " << in.pos[i];
        return o;
      }
      const double gap = pos.at(in.pos[i]).z - neg.at(in.neg[i]).z;
      if (in.neg[i] == in.pos[i]) EXPECT_EQ(gap, 0);  // a rim node: one node, no gap
      o.least = std::min(o.least, gap);
      o.most = std::max(o.most, gap);
      const Vec3& p = s.mesh.nodes[in.neg[i]];
      const double d = std::hypot(p.x - 9.5, p.y - 9.5);
      if (d < nearest) {
        nearest = d;
        o.centre = gap;
      }
    }
  }
  return o;
}

TEST(SplitMeshTest, CalculixOpensTheCrackUnderTension) {
  const SplitMesh s = Split(Crack());
  const auto o = CrackOpening(s, 0.02);  // a strain of 1e-3 on the rock's 30000
  if (!o) GTEST_SKIP() << "CalculiX (ccx, Debian's calculix-ccx) is not installed";
  // A penny crack of radius c under a remote stress σ opens 4(1 − ν²)σc/(πE) at its middle:
  // about 6e-3 here for c ≈ 5 (a square of side 10); the box's nearness makes it more.
  EXPECT_GT(o->centre, 3e-3);
  EXPECT_LT(o->most, 0.02);
  EXPECT_GT(o->least, -1e-6);
}

TEST(SplitMeshTest, CalculixKeepsTheFacesApartUnderCompression) {
  const SplitMesh s = Split(Crack());
  const auto pulled = CrackOpening(s, 0.02);
  if (!pulled) GTEST_SKIP() << "CalculiX (ccx, Debian's calculix-ccx) is not installed";
  const auto pressed = CrackOpening(s, -0.02);
  // Without the contact pair the faces would pass through each other by as much as the
  // tension opens them; the contact's penalty lets them overlap a few per cent of that.
  EXPECT_GT(pressed->least, -0.05 * pulled->centre);
}

}  // namespace
}  // namespace sheetmesh
