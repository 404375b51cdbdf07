// Exodus II output through the Exodus library (netCDF underneath). Kept apart from the
// text writers so that only this file sees exodusII.h.
#include <exodusII.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <set>

#include "absl/strings/str_cat.h"
#include "common/file_util.h"
#include "common/status_macros.h"
#include "common/version.h"
#include "worker/pipeline/tet/volume_mesh_io.h"

namespace sheetmesh {
namespace {

// An open Exodus file, closed (and its partial file removed unless committed) on
// destruction.
class ExodusFile {
 public:
  explicit ExodusFile(std::string part) : part_(std::move(part)) {}
  ~ExodusFile() {
    if (id_ >= 0) ex_close(id_);
    if (!committed_) std::filesystem::remove(part_);
  }
  absl::Status Create() {
    int cpu_ws = sizeof(double), io_ws = sizeof(double);
    id_ = ex_create(part_.c_str(), EX_CLOBBER, &cpu_ws, &io_ws);
    if (id_ < 0) return absl::InternalError(absl::StrCat(part_, ": Exodus cannot create the file"));
    return absl::OkStatus();
  }
  // kInternal naming the call when the library reports an error.
  absl::Status Check(int rc, const char* call) const {
    if (rc >= 0) return absl::OkStatus();
    return absl::InternalError(absl::StrCat(part_, ": Exodus ", call, " failed (", rc, ")"));
  }
  int id() const { return id_; }
  absl::Status Commit(const std::string& path) {
    SM_RETURN_IF_ERROR(Check(ex_close(id_), "ex_close"));
    id_ = -1;
    std::error_code ec;
    std::filesystem::rename(part_, path, ec);
    if (ec) return absl::InternalError(absl::StrCat(path, ": ", ec.message()));
    committed_ = true;
    return absl::OkStatus();
  }

 private:
  std::string part_;
  int id_ = -1;
  bool committed_ = false;
};

// TETRA4 sides: 1 = (1,2,4), 2 = (2,3,4), 3 = (1,4,3), 4 = (1,3,2).
constexpr int kTetSide[4][3] = {{0, 1, 3}, {1, 2, 3}, {0, 3, 2}, {0, 2, 1}};

// The Exodus side (1–4) of t with the nodes of q; 0 where t has no such face.
int TetSide(const Tet& t, const std::array<uint32_t, 3>& q) {
  const FaceKey key = SortedFace(q[0], q[1], q[2]);
  for (int k = 0; k < 4; ++k) {
    if (SortedFace(t[kTetSide[k][0]], t[kTetSide[k][1]], t[kTetSide[k][2]]) == key) return k + 1;
  }
  return 0;
}

// The tetrahedron face on each face of the box: (element number, Exodus side), tetrahedron t
// being element element_of[t].
std::vector<std::vector<std::pair<int, int>>> BoxSideSets(const TetMesh& m,
                                                          const std::vector<int>& side,
                                                          const std::vector<int>& element_of) {
  std::map<FaceKey, std::pair<int, int>> owner;
  for (size_t t = 0; t < m.tets.size(); ++t) {
    for (int k = 0; k < 4; ++k) {
      const Tet& q = m.tets[t];
      owner.emplace(SortedFace(q[kTetSide[k][0]], q[kTetSide[k][1]], q[kTetSide[k][2]]),
                    std::make_pair(element_of[t], k + 1));
    }
  }
  std::vector<std::vector<std::pair<int, int>>> sets(6);
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (side[f] < 0) continue;
    const auto it = owner.find(SortedFace(m.faces[f][0], m.faces[f][1], m.faces[f][2]));
    if (it != owner.end()) sets[side[f]].push_back(it->second);
  }
  return sets;
}

// The mesh (`split`'s where given: with the two sides of each sheet as side sets).
absl::Status WriteMesh(const std::string& path, const TetMesh& m, const SplitMesh* split) {
  const auto sheets = SheetFacesByPiece(m);
  // The tetrahedra by region (the rock, then each body), numbered in that order.
  std::map<int32_t, std::vector<size_t>> regions;
  regions[-1];
  for (size_t t = 0; t < m.tets.size(); ++t) regions[m.Region(t)].push_back(t);
  std::vector<int> element_of(m.tets.size());
  int next = 1;
  for (const auto& [piece, tets] : regions)
    for (size_t t : tets) element_of[t] = next++;
  const std::vector<int> side = BoxSides(m);
  auto side_sets = BoxSideSets(m, side, element_of);
  std::vector<std::string> set_names = {"box_xmin", "box_xmax", "box_ymin",
                                        "box_ymax", "box_zmin", "box_zmax"};
  std::vector<int> set_ids = {1, 2, 3, 4, 5, 6};
  if (split != nullptr) {
    for (const auto& [piece, faces] : sheets) {
      std::vector<std::pair<int, int>> neg, pos;
      for (const SheetInterface& in : split->interfaces) {
        if (in.piece != piece) continue;
        const int a = TetSide(m.tets[in.tet_neg], in.neg), b = TetSide(m.tets[in.tet_pos], in.pos);
        if (a == 0 || b == 0) {
          return absl::InternalError(
              absl::StrCat(path, ": sheet face ", in.face, " is no face of its tetrahedron"));
        }
        neg.emplace_back(element_of[in.tet_neg], a);
        pos.emplace_back(element_of[in.tet_pos], b);
      }
      side_sets.push_back(std::move(neg));
      side_sets.push_back(std::move(pos));
      set_names.push_back(absl::StrCat("sheet_", piece, "_neg"));
      set_names.push_back(absl::StrCat("sheet_", piece, "_pos"));
      set_ids.push_back(1000 + 2 * piece);
      set_ids.push_back(1001 + 2 * piece);
    }
  }
  size_t sheet_elems = 0;
  for (const auto& [p, faces] : sheets) sheet_elems += faces.size();
  ExodusFile file(path + ".part");
  SM_RETURN_IF_ERROR(file.Create());
  const int ex = file.id();
  // The title holds 80 characters: the units fit.
  const std::string title =
      absl::StrCat("sheetmesh ", SHEETMESH_VERSION, " volume mesh, ", m.UnitsText()).substr(0, 80);
  SM_RETURN_IF_ERROR(
      file.Check(ex_put_init(ex, title.c_str(), 3, static_cast<int64_t>(m.nodes.size()),
                             static_cast<int64_t>(m.tets.size() + sheet_elems),
                             static_cast<int64_t>(regions.size() + sheets.size()), 6,
                             static_cast<int64_t>(side_sets.size())),
                 "ex_put_init"));
  std::vector<double> x(m.nodes.size()), y(m.nodes.size()), z(m.nodes.size());
  for (size_t i = 0; i < m.nodes.size(); ++i) {
    x[i] = m.nodes[i].x;
    y[i] = m.nodes[i].y;
    z[i] = m.nodes[i].z;
  }
  SM_RETURN_IF_ERROR(file.Check(ex_put_coord(ex, x.data(), y.data(), z.data()), "ex_put_coord"));
  char cx[] = "x", cy[] = "y", cz[] = "z";
  char* coord_names[3] = {cx, cy, cz};
  SM_RETURN_IF_ERROR(file.Check(ex_put_coord_names(ex, coord_names), "ex_put_coord_names"));

  // Element blocks: the rock (id 1), each body (TETRA, id 100 + piece), then each sheet
  // (TRI3, id 100 + piece).
  auto block_id = [](int32_t piece) { return piece < 0 ? 1 : 100 + piece; };
  std::vector<int> conn;
  std::vector<std::string> block_names;
  for (const auto& [piece, tets] : regions) {
    SM_RETURN_IF_ERROR(file.Check(
        ex_put_elem_block(ex, block_id(piece), "TETRA", static_cast<int64_t>(tets.size()), 4, 0),
        "ex_put_elem_block"));
    conn.clear();
    for (size_t t : tets)
      for (uint32_t v : m.tets[t]) conn.push_back(static_cast<int>(v + 1));
    if (!tets.empty()) {
      SM_RETURN_IF_ERROR(
          file.Check(ex_put_elem_conn(ex, block_id(piece), conn.data()), "ex_put_elem_conn"));
    }
    block_names.push_back(piece < 0 ? std::string("rock") : absl::StrCat("body_", piece));
  }
  for (const auto& [piece, faces] : sheets) {
    const int id = 100 + piece;
    SM_RETURN_IF_ERROR(
        file.Check(ex_put_elem_block(ex, id, "TRI3", static_cast<int64_t>(faces.size()), 3, 0),
                   "ex_put_elem_block"));
    conn.clear();
    for (size_t f : faces)
      for (uint32_t v : m.faces[f]) conn.push_back(static_cast<int>(v + 1));
    SM_RETURN_IF_ERROR(file.Check(ex_put_elem_conn(ex, id, conn.data()), "ex_put_elem_conn"));
    block_names.push_back(absl::StrCat("sheet_", piece));
  }
  std::vector<char*> names;
  for (std::string& n : block_names) names.push_back(n.data());
  SM_RETURN_IF_ERROR(file.Check(ex_put_names(ex, EX_ELEM_BLOCK, names.data()), "ex_put_names"));

  // Side sets (the box's six faces, then each sheet's two sides) and the box's node sets.
  std::vector<char*> names_of_sets;
  for (std::string& n : set_names) names_of_sets.push_back(n.data());
  for (size_t k = 0; k < side_sets.size(); ++k) {
    std::vector<int> elems, sides;
    for (const auto& [e, s] : side_sets[k]) {
      elems.push_back(e);
      sides.push_back(s);
    }
    SM_RETURN_IF_ERROR(
        file.Check(ex_put_side_set_param(ex, set_ids[k], static_cast<int64_t>(elems.size()), 0),
                   "ex_put_side_set_param"));
    if (!elems.empty()) {
      SM_RETURN_IF_ERROR(file.Check(ex_put_side_set(ex, set_ids[k], elems.data(), sides.data()),
                                    "ex_put_side_set"));
    }
  }
  for (int k = 0; k < 6; ++k) {
    std::set<int> nodes;
    for (size_t f = 0; f < m.faces.size(); ++f)
      if (side[f] == k)
        for (uint32_t v : m.faces[f]) nodes.insert(static_cast<int>(v + 1));
    std::vector<int> node_list(nodes.begin(), nodes.end());
    SM_RETURN_IF_ERROR(
        file.Check(ex_put_node_set_param(ex, k + 1, static_cast<int64_t>(node_list.size()), 0),
                   "ex_put_node_set_param"));
    if (!node_list.empty()) {
      SM_RETURN_IF_ERROR(
          file.Check(ex_put_node_set(ex, k + 1, node_list.data()), "ex_put_node_set"));
    }
  }
  SM_RETURN_IF_ERROR(
      file.Check(ex_put_names(ex, EX_SIDE_SET, names_of_sets.data()), "ex_put_names"));
  SM_RETURN_IF_ERROR(
      file.Check(ex_put_names(ex, EX_NODE_SET, names_of_sets.data()), "ex_put_names"));

  // Element variables: the aperture and the cubic law on the sheets.
  if (!sheets.empty()) {
    char v0[] = "aperture", v1[] = "permeability", v2[] = "transmissivity";
    char* var_names[3] = {v0, v1, v2};
    SM_RETURN_IF_ERROR(file.Check(ex_put_var_param(ex, "e", 3), "ex_put_var_param"));
    SM_RETURN_IF_ERROR(file.Check(ex_put_var_names(ex, "e", 3, var_names), "ex_put_var_names"));
    // On every block (0 on the rock): readers such as meshio take element variables only
    // when every block has them.
    const int blocks = static_cast<int>(regions.size() + sheets.size());
    std::vector<int> truth(static_cast<size_t>(blocks) * 3, 1);
    SM_RETURN_IF_ERROR(
        file.Check(ex_put_elem_var_tab(ex, blocks, 3, truth.data()), "ex_put_elem_var_tab"));
    const double time = 0;
    SM_RETURN_IF_ERROR(file.Check(ex_put_time(ex, 1, &time), "ex_put_time"));
    for (const auto& [piece, tets] : regions) {
      const std::vector<double> zeros(tets.size(), 0.0);
      for (int v = 0; v < 3 && !tets.empty(); ++v) {
        SM_RETURN_IF_ERROR(
            file.Check(ex_put_elem_var(ex, 1, v + 1, block_id(piece),
                                       static_cast<int64_t>(zeros.size()), zeros.data()),
                       "ex_put_elem_var"));
      }
    }
    for (const auto& [piece, faces] : sheets) {
      for (int v = 0; v < 3; ++v) {
        std::vector<double> values;
        for (size_t f : faces) {
          const double a = m.FaceThickness(f);
          values.push_back(v == 0 ? a : v == 1 ? a * a / 12 : a * a * a / 12);
        }
        SM_RETURN_IF_ERROR(
            file.Check(ex_put_elem_var(ex, 1, v + 1, 100 + piece,
                                       static_cast<int64_t>(values.size()), values.data()),
                       "ex_put_elem_var"));
      }
    }
  }
  return file.Commit(path);
}

}  // namespace

absl::Status WriteExodus(const std::string& path, const TetMesh& m) {
  return WriteMesh(path, m, nullptr);
}

absl::Status WriteSplitExodus(const std::string& path, const SplitMesh& split) {
  return WriteMesh(path, split.mesh, &split);
}

}  // namespace sheetmesh
