#include "worker/pipeline/surface/mid_surface_box.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>
#include <utility>

#include "absl/container/flat_hash_map.h"
#include "worker/pipeline/mesh/vertex_normals.h"
#include "worker/pipeline/surface/mid_surface_chart.h"

namespace sheetmesh {

std::vector<uint8_t> OutlineCornersOnBox(const std::vector<Vec3>& vertices, const Dims& dims) {
  std::vector<uint8_t> out(vertices.size(), 0);
  for (size_t v = 0; v < vertices.size(); ++v) out[v] = BoxFacesAt(vertices[v], dims, 1e-6) >= 2;
  return out;
}

void ClipMeshToBox(const Dims& dims, std::vector<JunctionLine>* lines, TriangleMesh* mesh) {
  constexpr double kOnFace = 0.2;  // voxels
  const double extent[3] = {static_cast<double>(dims.nx), static_cast<double>(dims.ny),
                            static_cast<double>(dims.nz)};
  std::vector<Vec3>& v = mesh->vertices;
  std::vector<float>& thick = mesh->vertex_thickness_voxels;
  for (int k = 0; k < 3; ++k) {
    for (const double side : {-1.0, 1.0}) {
      const double bound = side < 0 ? -0.5 : extent[k] - 0.5;
      // Signed distance outside the face (> 0: outside).
      auto out = [&](uint32_t x) { return side * (v[x][k] - bound); };
      for (size_t x = 0; x < v.size(); ++x) {
        if (std::abs(out(static_cast<uint32_t>(x))) < kOnFace) {
          v[x][k] = bound;
        }
      }
      std::map<std::pair<uint32_t, uint32_t>, uint32_t> cut_at;
      auto cut = [&](uint32_t a, uint32_t b) {
        const auto key = std::minmax(a, b);
        const auto it = cut_at.find(key);
        if (it != cut_at.end()) return it->second;
        const double da = out(a), db = out(b);
        const double t = da / (da - db);
        const uint32_t id = static_cast<uint32_t>(v.size());
        Vec3 p = v[a] + (v[b] - v[a]) * t;
        p[k] = bound;
        v.push_back(p);
        thick.push_back(static_cast<float>(thick[a] + (thick[b] - thick[a]) * t));
        cut_at[key] = id;
        return id;
      };
      std::vector<Face> faces;
      std::vector<int32_t> piece;
      for (size_t f = 0; f < mesh->faces.size(); ++f) {
        const Face& t = mesh->faces[f];
        int outside = 0;
        for (uint32_t x : t) outside += out(x) > 0;
        const int32_t p = mesh->face_piece.empty() ? 0 : mesh->face_piece[f];
        if (outside == 0) {
          faces.push_back(t);
          piece.push_back(p);
          continue;
        }
        if (outside == 3) continue;
        // The polygon inside (Sutherland-Hodgman against one plane), as a fan.
        std::vector<uint32_t> poly;
        for (int e = 0; e < 3; ++e) {
          const uint32_t a = t[e], b = t[(e + 1) % 3];
          const bool a_in = out(a) <= 0, b_in = out(b) <= 0;
          if (a_in) poly.push_back(a);
          if (a_in != b_in && out(a) != 0 && out(b) != 0) poly.push_back(cut(a, b));
        }
        for (size_t e = 1; e + 1 < poly.size(); ++e) {
          const Face g = {poly[0], poly[e], poly[e + 1]};
          if (g[0] == g[1] || g[1] == g[2] || g[0] == g[2]) continue;
          if (Norm2(Cross(v[g[1]] - v[g[0]], v[g[2]] - v[g[0]])) < 1e-12) continue;
          faces.push_back(g);
          piece.push_back(p);
        }
      }
      mesh->faces = std::move(faces);
      mesh->face_piece = std::move(piece);
    }
  }
  // Compact.
  std::vector<uint32_t> index(v.size(), UINT32_MAX);
  std::vector<Vec3> kept;
  std::vector<float> kept_thick;
  for (Face& t : mesh->faces) {
    for (uint32_t& x : t) {
      if (index[x] == UINT32_MAX) {
        index[x] = static_cast<uint32_t>(kept.size());
        kept.push_back(v[x]);
        kept_thick.push_back(thick[x]);
      }
      x = index[x];
    }
  }
  v = std::move(kept);
  thick = std::move(kept_thick);
  for (JunctionLine& l : *lines) {
    for (uint32_t& x : l.vertex_of) {
      if (x != UINT32_MAX) x = index[x];
    }
  }
}

uint64_t SettleAtBox(const Dims& dims, TriangleMesh* mesh) {
  constexpr double kOnFace = 0.1;     // voxels: a rim vertex this near a face lies on it
  constexpr double kClear = 1.0;      // voxels: the others kept this far off
  constexpr double kLeaves = 0.2588;  // sin 15 degrees: the least slope slid along
  constexpr double kMostSlide = 1.5;  // voxels
  constexpr double kMostRim = 1.0;    // voxels: the most a rim vertex moves along a face
  std::vector<Vec3>& v = mesh->vertices;
  const std::vector<Face>& faces = mesh->faces;
  absl::flat_hash_map<uint64_t, int> uses;
  auto key = [](uint32_t a, uint32_t b) {
    return (static_cast<uint64_t>(std::min(a, b)) << 32) | std::max(a, b);
  };
  for (const Face& t : faces) {
    for (int k = 0; k < 3; ++k) ++uses[key(t[k], t[(k + 1) % 3])];
  }
  std::vector<uint8_t> rim(v.size(), 0), fixed(v.size(), 0);
  std::vector<int32_t> piece_of(v.size(), -1);
  std::vector<std::vector<uint32_t>> faces_of(v.size());
  for (uint32_t f = 0; f < faces.size(); ++f) {
    const Face& t = faces[f];
    const int32_t p = mesh->face_piece.empty() ? 0 : mesh->face_piece[f];
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = t[k], b = t[(k + 1) % 3];
      const int u = uses[key(a, b)];
      if (u == 1) rim[a] = rim[b] = 1;
      if (u > 2) fixed[a] = fixed[b] = 1;  // on a junction
      if (piece_of[a] >= 0 && piece_of[a] != p) fixed[a] = 1;
      piece_of[a] = p;
      faces_of[a].push_back(f);
    }
  }
  const std::vector<Vec3> normals = VertexNormals(v, faces);
  auto face_normal = [&](uint32_t f) {
    const Face& t = faces[f];
    return Cross(v[t[1]] - v[t[0]], v[t[2]] - v[t[0]]);
  };
  // Whether a face around x, with x back at `from`, turns over or by more than 60 degrees.
  auto Turns = [&](uint32_t x, const Vec3& from) {
    const Vec3 now_at = v[x];
    std::vector<Vec3> now;
    for (uint32_t f : faces_of[x]) now.push_back(face_normal(f));
    v[x] = from;
    bool turned = false;
    for (size_t i = 0; i < now.size() && !turned; ++i) {
      const Vec3 before = face_normal(faces_of[x][i]);
      turned = Dot(now[i], before) <= 0.5 * Norm(now[i]) * Norm(before);
    }
    v[x] = now_at;
    return turned;
  };
  const double extent[3] = {static_cast<double>(dims.nx), static_cast<double>(dims.ny),
                            static_cast<double>(dims.nz)};
  uint64_t moved = 0;
  for (uint32_t x = 0; x < v.size(); ++x) {
    if (faces_of[x].empty()) continue;
    for (int k = 0; k < 3; ++k) {
      for (const double side : {-1.0, 1.0}) {
        const double bound = side < 0 ? -0.5 : extent[k] - 0.5;
        const double d = -side * (v[x][k] - bound);  // > 0 inside
        if (rim[x]) {
          if (std::abs(d) >= kOnFace) continue;
          const Vec3 from = v[x];
          v[x][k] = bound;
          // Along the face onto the line where the sheet's plane near it (of its neighbours
          // off the box, two rings) meets the face: a straight rim, not the voxels' zig-zag.
          std::vector<Vec3> near;
          for (uint32_t f : faces_of[x]) {
            for (uint32_t y : faces[f]) {
              for (uint32_t g : faces_of[y]) {
                for (uint32_t z : faces[g]) {
                  if (!rim[z] && piece_of[z] == piece_of[x]) near.push_back(v[z]);
                }
              }
            }
          }
          std::sort(near.begin(), near.end(), [](const Vec3& a, const Vec3& b) {
            return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
          });
          near.erase(std::unique(near.begin(), near.end()), near.end());
          if (near.size() >= 4 && !fixed[x]) {
            Vec3 c, n;
            FitPlanePoints(near, &c, &n);
            Vec3 in_face = n;
            in_face[k] = 0;
            const double slope = Norm(in_face);
            const double s = -Dot(n, v[x] - c) / std::max(slope, 1e-12);
            if (slope >= kLeaves && std::abs(s) <= kMostRim) {
              const Vec3 on = v[x];
              v[x] = v[x] + in_face / slope * s;
              if (Turns(x, from)) v[x] = on;
            }
          }
          if (Turns(x, from)) v[x] = from;
          moved += !(v[x] == from);
          continue;
        }
        if (fixed[x] || d >= kClear) continue;
        Vec3 in(0, 0, 0);
        in[k] = -side;
        const Vec3& n = normals[x];
        Vec3 along = in - n * Dot(in, n);
        const double slope = Norm(along);
        if (slope < kLeaves) continue;
        along = along / slope;
        double step = std::min(kMostSlide, (kClear - d) / slope);
        const Vec3 from = v[x];
        for (int tries = 0; tries < 4; ++tries, step /= 2) {
          v[x] = from + along * step;
          if (!Turns(x, from)) break;
          v[x] = from;
        }
        moved += !(v[x] == from);
      }
    }
  }
  return moved;
}

}  // namespace sheetmesh
