// Abaqus/CalculiX input decks: the volume mesh with its sheets as shell elements, or split
// along the sheets with cohesive elements (Abaqus) or contact pairs (CalculiX) between the
// two sides.
#include <algorithm>
#include <map>
#include <set>

#include "absl/container/flat_hash_map.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/file_util.h"
#include "common/status_macros.h"
#include "common/version.h"
#include "worker/pipeline/tet/volume_mesh_io.h"

namespace sheetmesh {
namespace {

// C3D4 face numbering: S1 = (1,2,3), S2 = (1,4,2), S3 = (2,4,3), S4 = (3,4,1).
constexpr int kC3d4Face[4][3] = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {2, 3, 0}};

// The C3D4 face (1–4) of t with the nodes of q; 0 where t has no such face.
int C3d4Face(const Tet& t, const std::array<uint32_t, 3>& q) {
  const FaceKey key = SortedFace(q[0], q[1], q[2]);
  for (int k = 0; k < 4; ++k) {
    if (SortedFace(t[kC3d4Face[k][0]], t[kC3d4Face[k][1]], t[kC3d4Face[k][2]]) == key) {
      return k + 1;
    }
  }
  return 0;
}

// A node set, sixteen 1-based ids to a line.
void AppendNodeSet(std::string* out, const std::string& name, const std::set<uint32_t>& nodes) {
  absl::StrAppend(out, "*NSET, NSET=", name, "\n");
  int n = 0;
  for (uint32_t v : nodes) absl::StrAppend(out, v + 1, ++n % 16 == 0 ? "\n" : ", ");
  if (n % 16 != 0) *out += "\n";
}

double MeanThickness(const TetMesh& m, const std::vector<size_t>& faces) {
  double sum = 0;
  for (size_t f : faces) sum += m.FaceThickness(f);
  return faces.empty() ? 0 : sum / faces.size();
}

// The deck of `m`; `split` (whose mesh `m` is) adds the two sides of each sheet and carries
// the sheets as cohesive elements, or as contact pairs where `calculix`.
absl::StatusOr<std::string> Deck(const std::string& path, const TetMesh& m, const SplitMesh* split,
                                 bool calculix) {
  const auto sheets = SheetFacesByPiece(m);
  std::string out = absl::StrCat(
      "*HEADING\nsheetmesh ", SHEETMESH_VERSION, " volume mesh: rock tetrahedra ",
      split == nullptr ? "with sheet faces"
                       : (calculix ? "split along the sheets, contact pairs between the sides"
                                   : "split along the sheets, cohesive elements between the sides"),
      "\n** ", m.UnitsText(), "\n*NODE\n");
  for (size_t i = 0; i < m.nodes.size(); ++i) {
    absl::StrAppendFormat(&out, "%d, %.12g, %.12g, %.12g\n", i + 1, m.nodes[i].x, m.nodes[i].y,
                          m.nodes[i].z);
  }
  // The tetrahedra by region: ELSET=ROCK, ELSET=BODY_<p> for each body.
  std::map<int32_t, std::vector<size_t>> regions;
  regions[-1];
  for (size_t t = 0; t < m.tets.size(); ++t) regions[m.Region(t)].push_back(t);
  std::vector<size_t> element_of(m.tets.size());
  size_t id = 1;
  for (const auto& [piece, tets] : regions) {
    if (tets.empty()) continue;
    absl::StrAppend(&out, "*ELEMENT, TYPE=C3D4, ELSET=",
                    piece < 0 ? std::string("ROCK") : absl::StrCat("BODY_", piece), "\n");
    for (size_t i : tets) {
      const Tet& t = m.tets[i];
      element_of[i] = id;
      absl::StrAppend(&out, id++, ", ", t[0] + 1, ", ", t[1] + 1, ", ", t[2] + 1, ", ", t[3] + 1,
                      "\n");
    }
  }
  // The sheets' elements: shells on the faces, or cohesive wedges across the split.
  std::map<int32_t, std::vector<const SheetInterface*>> sides;
  if (split != nullptr) {
    for (const SheetInterface& in : split->interfaces) sides[in.piece].push_back(&in);
  }
  if (split == nullptr) {
    for (const auto& [piece, faces] : sheets) {
      absl::StrAppend(&out, "*ELEMENT, TYPE=S3, ELSET=SHEET_", piece, "\n");
      for (size_t f : faces) {
        const auto& t = m.faces[f];
        absl::StrAppend(&out, id++, ", ", t[0] + 1, ", ", t[1] + 1, ", ", t[2] + 1, "\n");
      }
    }
  } else if (!calculix) {
    for (const auto& [piece, list] : sides) {
      absl::StrAppend(&out, "*ELEMENT, TYPE=COH3D6, ELSET=SHEET_", piece, "\n");
      for (const SheetInterface* in : list) {
        if (in->Closed()) continue;
        absl::StrAppend(&out, id++, ", ", in->neg[0] + 1, ", ", in->neg[1] + 1, ", ",
                        in->neg[2] + 1, ", ", in->pos[0] + 1, ", ", in->pos[1] + 1, ", ",
                        in->pos[2] + 1, "\n");
      }
    }
  }
  // Node sets on the box's sides, for boundary conditions; on the sheets' sides where split.
  static const char* kSide[6] = {"XMIN", "XMAX", "YMIN", "YMAX", "ZMIN", "ZMAX"};
  const std::vector<int> side = BoxSides(m);
  for (int k = 0; k < 6; ++k) {
    std::set<uint32_t> nodes;
    for (size_t f = 0; f < m.faces.size(); ++f)
      if (side[f] == k) nodes.insert(m.faces[f].begin(), m.faces[f].end());
    if (!nodes.empty()) AppendNodeSet(&out, absl::StrCat("BOX_", kSide[k]), nodes);
  }
  for (const auto& [piece, list] : sides) {
    std::set<uint32_t> neg, pos;
    for (const SheetInterface* in : list) {
      neg.insert(in->neg.begin(), in->neg.end());
      pos.insert(in->pos.begin(), in->pos.end());
    }
    AppendNodeSet(&out, absl::StrCat("SHEET_", piece, "_NEG"), neg);
    AppendNodeSet(&out, absl::StrCat("SHEET_", piece, "_POS"), pos);
  }
  // Surfaces on the tetrahedra's faces.
  absl::flat_hash_map<FaceKey, std::pair<size_t, int>> owner;
  for (size_t t = 0; t < m.tets.size(); ++t) {
    for (int k = 0; k < 4; ++k) {
      const Tet& q = m.tets[t];
      owner.emplace(SortedFace(q[kC3d4Face[k][0]], q[kC3d4Face[k][1]], q[kC3d4Face[k][2]]),
                    std::make_pair(element_of[t], k + 1));
    }
  }
  for (const auto& [piece, faces] : FaceGroups(m)) {
    if (split != nullptr && piece >= 0 && !m.IsBody(piece)) continue;  // by side, below
    absl::StrAppend(&out, "*SURFACE, TYPE=ELEMENT, NAME=SURF_",
                    piece < 0 ? std::string("BOUNDARY")
                              : absl::StrCat(m.IsBody(piece) ? "BODY_" : "SHEET_", piece),
                    "\n");
    for (size_t f : faces) {
      auto it = owner.find(SortedFace(m.faces[f][0], m.faces[f][1], m.faces[f][2]));
      if (it == owner.end()) {
        return absl::InternalError(absl::StrCat(path, ": face ", f, " belongs to no tetrahedron"));
      }
      absl::StrAppend(&out, it->second.first, ", S", it->second.second, "\n");
    }
  }
  for (const auto& [piece, list] : sides) {
    for (const bool pos : {false, true}) {
      absl::StrAppend(&out, "*SURFACE, TYPE=ELEMENT, NAME=SURF_SHEET_", piece,
                      pos ? "_POS" : "_NEG", "\n");
      for (const SheetInterface* in : list) {
        const uint32_t t = pos ? in->tet_pos : in->tet_neg;
        const int face = C3d4Face(m.tets[t], pos ? in->pos : in->neg);
        if (face == 0) {
          return absl::InternalError(
              absl::StrCat(path, ": sheet face ", in->face, " is no face of its tetrahedron"));
        }
        absl::StrAppend(&out, element_of[t], ", S", face, "\n");
      }
    }
  }
  // Materials and sections: without a section CalculiX refuses the elements. The elastic
  // constants are placeholders in the mesh's units; replace them for a real analysis.
  out +=
      "** Materials: placeholder elastic constants (Young's modulus, Poisson's ratio);\n"
      "** replace them with the rock's and the fill's in the mesh's units.\n"
      "*MATERIAL, NAME=ROCK\n*ELASTIC\n30000., 0.25\n";
  if (split == nullptr) {
    out += "*MATERIAL, NAME=FRACTURE\n*ELASTIC\n3000., 0.3\n";
  } else if (!calculix) {
    out +=
        "** The fractures' traction-separation stiffness (normal, two shear; stress per length):\n"
        "** a placeholder to replace.\n"
        "*MATERIAL, NAME=FRACTURE\n*ELASTIC, TYPE=TRACTION\n1000., 1000., 1000.\n";
  }
  if (regions.size() > 1) out += "*MATERIAL, NAME=FILL\n*ELASTIC\n3000., 0.3\n";
  for (const auto& [piece, tets] : regions) {
    if (tets.empty()) continue;
    if (piece < 0) {
      out += "*SOLID SECTION, ELSET=ROCK, MATERIAL=ROCK\n";
    } else {
      absl::StrAppend(&out, "*SOLID SECTION, ELSET=BODY_", piece, ", MATERIAL=FILL\n");
    }
  }
  const double vox = m.voxel_length > 0 ? m.voxel_length : 1.0;
  for (const auto& [piece, faces] : sheets) {
    const double mean = MeanThickness(m, faces);
    absl::StrAppendFormat(&out,
                          "** sheet %d: mean thickness %.7g (%.4g voxels) over %d triangles\n",
                          piece, mean, mean / vox, faces.size());
    if (split == nullptr) {
      absl::StrAppendFormat(&out, "*SHELL SECTION, ELSET=SHEET_%d, MATERIAL=FRACTURE\n%.7g\n",
                            piece, mean > 0 ? mean : vox);
    } else if (!calculix) {
      // A constitutive thickness of 1: the separation is the opening itself.
      absl::StrAppendFormat(&out,
                            "*COHESIVE SECTION, ELSET=SHEET_%d, MATERIAL=FRACTURE, "
                            "RESPONSE=TRACTION SEPARATION, THICKNESS=SPECIFIED\n1.\n",
                            piece);
    } else {
      // The fracture's faces may open and slide; pressed together they resist by a stiff
      // linear law (a penalty of the rock's modulus over a hundredth of the mean thickness).
      const double slope = 30000. / (0.01 * (mean > 0 ? mean : vox));
      absl::StrAppendFormat(&out,
                            "*SURFACE INTERACTION, NAME=FRACTURE_%d\n"
                            "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n%.7g\n"
                            "*CONTACT PAIR, INTERACTION=FRACTURE_%d, TYPE=SURFACE TO SURFACE\n"
                            "SURF_SHEET_%d_NEG, SURF_SHEET_%d_POS\n",
                            piece, slope, piece, piece, piece);
    }
  }
  return out;
}

}  // namespace

absl::Status WriteAbaqus(const std::string& path, const TetMesh& m) {
  SM_ASSIGN_OR_RETURN(std::string out, Deck(path, m, nullptr, false));
  return WriteFileAtomically(path, out);
}

absl::Status WriteSplitAbaqus(const std::string& path, const SplitMesh& split, bool calculix) {
  SM_ASSIGN_OR_RETURN(std::string out, Deck(path, split.mesh, &split, calculix));
  return WriteFileAtomically(path, out);
}

}  // namespace sheetmesh
