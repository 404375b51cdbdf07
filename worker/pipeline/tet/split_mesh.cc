#include "worker/pipeline/tet/split_mesh.h"

#include <algorithm>
#include <numeric>

#include "absl/container/flat_hash_set.h"
#include "absl/strings/str_cat.h"

namespace sheetmesh {
namespace {

// The tetrahedron across each face of each tetrahedron (slot 4t + k, the face opposite vertex
// k), -1 on the mesh's boundary; and every face key with its slot, sorted.
struct FaceIndex {
  std::vector<int64_t> across;
  std::vector<std::pair<FaceKey, uint32_t>> slots;

  explicit FaceIndex(const TetMesh& m) {
    slots.reserve(4 * m.tets.size());
    for (size_t t = 0; t < m.tets.size(); ++t)
      for (int k = 0; k < 4; ++k)
        slots.emplace_back(TetFace(m.tets[t], k), static_cast<uint32_t>(4 * t + k));
    std::sort(slots.begin(), slots.end());
    across.assign(slots.size(), -1);
    for (size_t i = 0; i + 1 < slots.size(); ++i) {
      if (slots[i].first != slots[i + 1].first) continue;
      across[slots[i].second] = slots[i + 1].second / 4;
      across[slots[i + 1].second] = slots[i].second / 4;
    }
  }
  // The tetrahedra having `key` as a face (one or two).
  std::vector<uint32_t> TetsOf(const FaceKey& key) const {
    std::vector<uint32_t> out;
    auto it = std::lower_bound(slots.begin(), slots.end(), std::make_pair(key, uint32_t{0}));
    for (; it != slots.end() && it->first == key; ++it) out.push_back(it->second / 4);
    return out;
  }
};

int SlotOf(const Tet& t, uint32_t v) {
  for (int k = 0; k < 4; ++k)
    if (t[k] == v) return k;
  return -1;
}

uint32_t Find(std::vector<uint32_t>& up, uint32_t i) {
  while (up[i] != i) i = up[i] = up[up[i]];
  return i;
}

}  // namespace

absl::StatusOr<SplitMesh> SplitAlongSheets(const TetMesh& m) {
  SplitMesh out;
  out.mesh = m;
  const size_t nv = m.nodes.size();
  out.parent.resize(nv);
  std::iota(out.parent.begin(), out.parent.end(), 0u);
  const FaceIndex index(m);

  absl::flat_hash_set<FaceKey> sheet_keys;
  std::vector<char> on_sheet(nv, 0);
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (m.face_piece[f] < 0 || m.IsBody(m.face_piece[f])) continue;
    const auto& q = m.faces[f];
    sheet_keys.insert(SortedFace(q[0], q[1], q[2]));
    for (uint32_t v : q) on_sheet[v] = 1;
  }
  // The regions the sheets cut the mesh into: tetrahedra that reach each other across faces
  // that are not sheet faces. A region of fewer than kGluedRegionTets tetrahedra (a sliver
  // of rock that sheets crossing close together enclose: one tetrahedron on the sample
  // phantom at r = 7) would float free in the split mesh, held by contact alone, and a
  // static solve has no answer there (CalculiX: "too many cutbacks"): its faces stay glued
  // to their neighbours, as rock.
  constexpr size_t kGluedRegionTets = 8;
  std::vector<uint32_t> region(m.tets.size());
  std::iota(region.begin(), region.end(), 0u);
  for (size_t t = 0; t < m.tets.size(); ++t) {
    for (int k = 0; k < 4; ++k) {
      const int64_t u = index.across[4 * t + k];
      if (u < 0 || sheet_keys.contains(TetFace(m.tets[t], k))) continue;
      region[Find(region, static_cast<uint32_t>(t))] = Find(region, static_cast<uint32_t>(u));
    }
  }
  std::vector<uint32_t> region_size(m.tets.size(), 0);
  for (size_t t = 0; t < m.tets.size(); ++t) ++region_size[Find(region, static_cast<uint32_t>(t))];
  std::vector<char> glued(m.tets.size(), 0);
  for (size_t t = 0; t < m.tets.size(); ++t) {
    const uint32_t root = Find(region, static_cast<uint32_t>(t));
    glued[t] = region_size[root] < kGluedRegionTets;
    if (glued[t] && root == t) ++out.stats.glued_regions;
  }
  // The tetrahedra around each sheet node, in increasing order.
  std::vector<uint32_t> start(nv + 1, 0);
  for (const Tet& t : m.tets)
    for (uint32_t v : t)
      if (on_sheet[v]) ++start[v + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<uint32_t> around(start[nv]), fill(start.begin(), start.end() - 1);
  for (size_t t = 0; t < m.tets.size(); ++t)
    for (uint32_t v : m.tets[t])
      if (on_sheet[v]) around[fill[v]++] = static_cast<uint32_t>(t);

  // Each sheet node's tetrahedra fall into sides: those that reach each other across faces
  // that are not sheet faces. The first side (by its lowest tetrahedron) keeps the node.
  std::vector<uint32_t> up, side_node;
  for (uint32_t v = 0; v < nv; ++v) {
    if (!on_sheet[v]) continue;
    ++out.stats.sheet_nodes;
    const uint32_t* tets = around.data() + start[v];
    const uint32_t n = start[v + 1] - start[v];
    up.resize(n);
    std::iota(up.begin(), up.end(), 0u);
    for (uint32_t i = 0; i < n; ++i) {
      const Tet& t = m.tets[tets[i]];
      for (int k = 0; k < 4; ++k) {
        if (t[k] == v) continue;
        const int64_t u = index.across[4 * size_t{tets[i]} + k];
        if (u < 0) continue;
        if (sheet_keys.contains(TetFace(t, k)) && !glued[tets[i]] && !glued[u]) continue;
        const uint32_t* j = std::lower_bound(tets, tets + n, static_cast<uint32_t>(u));
        if (j != tets + n && *j == u) up[Find(up, i)] = Find(up, static_cast<uint32_t>(j - tets));
      }
    }
    side_node.assign(n, UINT32_MAX);
    size_t sides = 0;
    for (uint32_t i = 0; i < n; ++i) {
      uint32_t& id = side_node[Find(up, i)];
      if (id == UINT32_MAX) {
        id = sides++ == 0 ? v : static_cast<uint32_t>(out.mesh.nodes.size());
        if (id != v) {
          out.mesh.nodes.push_back(m.nodes[v]);
          out.parent.push_back(v);
        }
      }
      out.mesh.tets[tets[i]][SlotOf(m.tets[tets[i]], v)] = id;
    }
    if (sides == 1) ++out.stats.rim_nodes;
  }
  out.stats.added_nodes = out.mesh.nodes.size() - nv;

  // The faces on the copies of a tetrahedron they bound; sheet faces become interfaces.
  const auto copies = [&](uint32_t t, const std::array<uint32_t, 3>& q) {
    std::array<uint32_t, 3> c;
    for (int i = 0; i < 3; ++i) c[i] = out.mesh.tets[t][SlotOf(m.tets[t], q[i])];
    return c;
  };
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const auto& q = m.faces[f];
    const std::vector<uint32_t> tets = index.TetsOf(SortedFace(q[0], q[1], q[2]));
    const int32_t piece = m.face_piece[f];
    if (tets.empty()) {
      return absl::InternalError(absl::StrCat("volume mesh: face ", f, " bounds no tetrahedron"));
    }
    out.mesh.faces[f] = copies(tets[0], q);
    if (piece < 0 || m.IsBody(piece)) continue;
    // A sheet face with rock on one side only (on the box's face), or whose two tetrahedra
    // do not lie on opposite sides of it, is left whole and counted: it has nothing to open.
    if (tets.size() != 2) {
      ++out.stats.unsplit_faces;
      continue;
    }
    const Vec3 n = Cross(m.nodes[q[1]] - m.nodes[q[0]], m.nodes[q[2]] - m.nodes[q[0]]);
    double side[2];
    for (int s = 0; s < 2; ++s) {
      const Tet& t = m.tets[tets[s]];
      const uint32_t apex = t[0] + t[1] + t[2] + t[3] - q[0] - q[1] - q[2];
      side[s] = Dot(n, m.nodes[apex] - m.nodes[q[0]]);
    }
    if (!(side[0] * side[1] < 0)) {
      ++out.stats.unsplit_faces;
      continue;
    }
    SheetInterface in;
    in.face = f;
    in.piece = piece;
    in.thickness_voxels = m.face_thickness_voxels[f];
    in.tet_neg = side[0] < 0 ? tets[0] : tets[1];
    in.tet_pos = side[0] < 0 ? tets[1] : tets[0];
    in.neg = copies(in.tet_neg, q);
    in.pos = copies(in.tet_pos, q);
    out.stats.closed_faces += in.Closed();
    out.mesh.faces[f] = in.neg;
    out.interfaces.push_back(in);
  }
  out.stats.interfaces = out.interfaces.size();
  std::stable_sort(
      out.interfaces.begin(), out.interfaces.end(),
      [](const SheetInterface& a, const SheetInterface& b) { return a.piece < b.piece; });
  return out;
}

}  // namespace sheetmesh
