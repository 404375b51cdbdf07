#include "worker/pipeline/tet/tet_regions.h"

#include <algorithm>
#include <map>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {

std::vector<int32_t> AssignRegions(const TetMesh& mesh, const TriangleMesh& surface,
                                   const Placement& placement) {
  if (surface.body_pieces.empty()) return {};
  // The faces that bound bodies: no region crosses them.
  absl::flat_hash_set<FaceKey> walls;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (surface.IsBody(mesh.face_piece[f])) {
      walls.insert(SortedFace(mesh.faces[f][0], mesh.faces[f][1], mesh.faces[f][2]));
    }
  }
  // Regions by a flood over the faces tetrahedra share.
  absl::flat_hash_map<FaceKey, uint32_t> first;  // a face's first tetrahedron
  std::vector<uint32_t> parent(mesh.tets.size());
  for (uint32_t t = 0; t < parent.size(); ++t) parent[t] = t;
  auto find = [&](uint32_t t) {
    while (parent[t] != t) t = parent[t] = parent[parent[t]];
    return t;
  };
  for (uint32_t t = 0; t < mesh.tets.size(); ++t) {
    for (int k = 0; k < 4; ++k) {
      const FaceKey key = TetFace(mesh.tets[t], k);
      if (walls.contains(key)) continue;
      auto [it, fresh] = first.try_emplace(key, t);
      if (!fresh) parent[find(t)] = find(it->second);
    }
  }
  std::map<uint32_t, std::vector<uint32_t>> members;
  for (uint32_t t = 0; t < mesh.tets.size(); ++t) {
    std::vector<uint32_t>& m = members[find(t)];
    if (m.size() < 64) m.push_back(t);
  }
  // Each body's surface, physical.
  std::vector<Vec3> vertices;
  vertices.reserve(surface.vertices.size());
  for (const Vec3& v : surface.vertices) vertices.push_back(placement.ToPhysical(v));
  std::map<int32_t, std::vector<Face>> body_faces;
  for (size_t f = 0; f < surface.faces.size(); ++f) {
    if (surface.IsBodyFace(f)) body_faces[surface.face_piece[f]].push_back(surface.faces[f]);
  }
  absl::flat_hash_map<uint32_t, int32_t> region_of;
  for (const auto& [root, tets] : members) {
    std::map<int32_t, size_t> votes;
    for (uint32_t t : tets) {
      const Tet& q = mesh.tets[t];
      const Vec3 c =
          (mesh.nodes[q[0]] + mesh.nodes[q[1]] + mesh.nodes[q[2]] + mesh.nodes[q[3]]) / 4;
      int32_t in = -1;
      for (const auto& [piece, faces] : body_faces) {
        if (InsideClosedSurface(c, vertices, faces)) {
          in = piece;
          break;
        }
      }
      ++votes[in];
    }
    int32_t best = -1;
    size_t most = 0;
    for (const auto& [piece, n] : votes) {
      if (n > most) best = piece, most = n;
    }
    region_of[root] = best;
  }
  std::vector<int32_t> out(mesh.tets.size());
  for (uint32_t t = 0; t < mesh.tets.size(); ++t) out[t] = region_of[find(t)];
  return out;
}

}  // namespace sheetmesh
