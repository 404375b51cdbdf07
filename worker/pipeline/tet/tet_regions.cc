#include "worker/pipeline/tet/tet_regions.h"

#include <algorithm>
#include <map>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"

namespace sheetmesh {

bool InsideClosedSurface(const Vec3& p, const std::vector<Vec3>& vertices,
                         const std::vector<Face>& faces) {
  // Offsets keep the ray off edges and vertices lying on round coordinates.
  const double py = p.y + 1.2345e-7 * (1 + std::abs(p.y));
  const double pz = p.z + 2.3456e-7 * (1 + std::abs(p.z));
  bool inside = false;
  for (const Face& f : faces) {
    const Vec3 &a = vertices[f[0]], &b = vertices[f[1]], &c = vertices[f[2]];
    if (std::max({a.x, b.x, c.x}) < p.x) continue;
    const Vec3 t[3] = {a, b, c};
    double e[3];
    for (int k = 0; k < 3; ++k) {
      const Vec3& u = t[k];
      const Vec3& v = t[(k + 1) % 3];
      e[k] = (v.y - u.y) * (pz - u.z) - (v.z - u.z) * (py - u.y);
    }
    if (!((e[0] > 0 && e[1] > 0 && e[2] > 0) || (e[0] < 0 && e[1] < 0 && e[2] < 0))) continue;
    const double x = (e[1] * a.x + e[2] * b.x + e[0] * c.x) / (e[0] + e[1] + e[2]);
    if (x > p.x) inside = !inside;
  }
  return inside;
}

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
