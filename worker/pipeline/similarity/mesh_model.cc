#include "worker/pipeline/similarity/mesh_model.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {

VoxelSet VoxelSetFromSortedLinear(const Dims& dims, std::span<const uint64_t> keys) {
  VoxelSet::Builder b(dims);
  const uint64_t nx = static_cast<uint64_t>(dims.nx);
  size_t i = 0;
  while (i < keys.size()) {
    const uint64_t row = keys[i] / nx;
    const uint64_t x0 = keys[i] % nx;
    size_t j = i + 1;
    while (j < keys.size() && keys[j] == keys[j - 1] + 1 && keys[j] / nx == row) ++j;
    b.AddRun(static_cast<int64_t>(row % dims.ny), static_cast<int64_t>(row / dims.ny),
             static_cast<int64_t>(x0), static_cast<int64_t>(x0 + (j - i)));
    i = j;
  }
  return std::move(b).Build();
}

namespace {

absl::StatusOr<VoxelSet> Collect(tbb::combinable<std::vector<uint64_t>>& parts, const Dims& dims) {
  std::vector<uint64_t> keys;
  parts.combine_each([&](std::vector<uint64_t>& p) {
    keys.insert(keys.end(), p.begin(), p.end());
    p = {};
  });
  tbb::parallel_sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return VoxelSetFromSortedLinear(dims, keys);
}

}  // namespace

absl::StatusOr<VoxelSet> VoxelizePrisms(const TriangleMesh& mesh, const Dims& dims,
                                        PrismHeight height, const Progress& progress) {
  if (height == PrismHeight::kFace && mesh.face_thickness_voxels.size() != mesh.faces.size()) {
    return absl::InvalidArgumentError(
        absl::StrCat("prism model needs a thickness per face: ", mesh.face_thickness_voxels.size(),
                     " for ", mesh.faces.size(), " faces"));
  }
  if (height == PrismHeight::kVertex &&
      mesh.vertex_thickness_voxels.size() != mesh.vertices.size()) {
    return absl::InvalidArgumentError(absl::StrCat(
        "shell model needs a thickness per vertex: ", mesh.vertex_thickness_voxels.size(), " for ",
        mesh.vertices.size(), " vertices"));
  }
  tbb::combinable<std::vector<uint64_t>> parts;
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, mesh.faces.size(), 256),
      [&](const tbb::blocked_range<size_t>& r) {
        std::vector<uint64_t>& out = parts.local();
        for (size_t f = r.begin(); f < r.end(); ++f) {
          const Face& face = mesh.faces[f];
          const Triangle t = Corners(mesh, f);
          double h[3];
          for (int k = 0; k < 3; ++k) {
            h[k] = height == PrismHeight::kFace ? mesh.face_thickness_voxels[f]
                                                : mesh.vertex_thickness_voxels[face[k]];
          }
          const double hmax = std::max({h[0], h[1], h[2]});
          if (!(hmax > 0)) continue;
          const Vec3 n = UnitNormal(t);
          if (Norm2(n) == 0) continue;
          // The prism lies within hmax / 2 of the triangle.
          const double pad = hmax / 2;
          int64_t lo[3], hi[3];
          for (int k = 0; k < 3; ++k) {
            const double mn = std::min({t[0][k], t[1][k], t[2][k]}) - pad;
            const double mx = std::max({t[0][k], t[1][k], t[2][k]}) + pad;
            const int64_t extent = k == 0 ? dims.nx : (k == 1 ? dims.ny : dims.nz);
            lo[k] = std::max<int64_t>(0, static_cast<int64_t>(std::ceil(mn - 1e-9)));
            hi[k] = std::min<int64_t>(extent - 1, static_cast<int64_t>(std::floor(mx + 1e-9)));
          }
          for (int64_t z = lo[2]; z <= hi[2]; ++z) {
            for (int64_t y = lo[1]; y <= hi[1]; ++y) {
              for (int64_t x = lo[0]; x <= hi[0]; ++x) {
                const Vec3 p(x, y, z);
                const double dist = Dot(p - t[0], n);
                if (std::abs(dist) > pad + 1e-9) continue;
                double u, v, w;
                if (!ProjectBarycentric(p, t, &u, &v, &w)) continue;
                if (u < -1e-9 || v < -1e-9 || w < -1e-9) continue;
                const double hh = u * h[0] + v * h[1] + w * h[2];
                if (std::abs(dist) > hh / 2 + 1e-9) continue;
                out.push_back(static_cast<uint64_t>((z * dims.ny + y) * dims.nx + x));
              }
            }
          }
        }
      });
  SM_RETURN_IF_ERROR(progress.Update(0.7));
  return Collect(parts, dims);
}

absl::StatusOr<VoxelSet> VoxelizeClosedSurface(const TriangleMesh& mesh, const Dims& dims,
                                               const Progress& progress) {
  // Rays along +x through (y + ey, z + ez): the small offsets keep them off edges and
  // vertices that sit on integer coordinates, so no crossing is counted twice.
  constexpr double ey = 1.2345e-6, ez = 2.3456e-6;
  struct Crossing {
    uint64_t row;
    double x;
    bool operator<(const Crossing& o) const { return row != o.row ? row < o.row : x < o.x; }
  };
  tbb::combinable<std::vector<Crossing>> parts;
  tbb::parallel_for(
      tbb::blocked_range<size_t>(0, mesh.faces.size(), 256),
      [&](const tbb::blocked_range<size_t>& r) {
        std::vector<Crossing>& out = parts.local();
        for (size_t f = r.begin(); f < r.end(); ++f) {
          const Triangle t = Corners(mesh, f);
          const double ymin = std::min({t[0].y, t[1].y, t[2].y}),
                       ymax = std::max({t[0].y, t[1].y, t[2].y});
          const double zmin = std::min({t[0].z, t[1].z, t[2].z}),
                       zmax = std::max({t[0].z, t[1].z, t[2].z});
          const int64_t y0 = std::max<int64_t>(0, static_cast<int64_t>(std::ceil(ymin - ey)));
          const int64_t y1 =
              std::min<int64_t>(dims.ny - 1, static_cast<int64_t>(std::floor(ymax - ey)));
          const int64_t z0 = std::max<int64_t>(0, static_cast<int64_t>(std::ceil(zmin - ez)));
          const int64_t z1 =
              std::min<int64_t>(dims.nz - 1, static_cast<int64_t>(std::floor(zmax - ez)));
          for (int64_t z = z0; z <= z1; ++z) {
            for (int64_t y = y0; y <= y1; ++y) {
              const double py = y + ey, pz = z + ez;
              // Point-in-triangle in the (y, z) projection, by edge functions.
              double e[3];
              for (int k = 0; k < 3; ++k) {
                const Vec3& a = t[k];
                const Vec3& b = t[(k + 1) % 3];
                e[k] = (b.y - a.y) * (pz - a.z) - (b.z - a.z) * (py - a.y);
              }
              const bool inside =
                  (e[0] > 0 && e[1] > 0 && e[2] > 0) || (e[0] < 0 && e[1] < 0 && e[2] < 0);
              if (!inside) continue;
              const double sum = e[0] + e[1] + e[2];
              // Barycentric weights: e[k] weights the vertex opposite edge k.
              const double x = (e[1] * t[0].x + e[2] * t[1].x + e[0] * t[2].x) / sum;
              out.push_back({static_cast<uint64_t>(z * dims.ny + y), x});
            }
          }
        }
      });
  std::vector<Crossing> crossings;
  parts.combine_each(
      [&](std::vector<Crossing>& p) { crossings.insert(crossings.end(), p.begin(), p.end()); });
  tbb::parallel_sort(crossings.begin(), crossings.end());
  SM_RETURN_IF_ERROR(progress.Update(0.6));
  VoxelSet::Builder b(dims);
  for (size_t i = 0; i < crossings.size();) {
    size_t j = i;
    while (j < crossings.size() && crossings[j].row == crossings[i].row) ++j;
    const int64_t y = static_cast<int64_t>(crossings[i].row % dims.ny);
    const int64_t z = static_cast<int64_t>(crossings[i].row / dims.ny);
    // Inside between crossings 2k and 2k+1: voxel centres x with a < x < b.
    for (size_t k = i; k + 1 < j; k += 2) {
      const int64_t x0 = static_cast<int64_t>(std::floor(crossings[k].x)) + 1;
      const int64_t x1 = static_cast<int64_t>(std::ceil(crossings[k + 1].x));
      if (x0 < x1) b.AddRun(y, z, x0, x1);
    }
    i = j;
  }
  return std::move(b).Build();
}

absl::StatusOr<VoxelSet> VoxelizeMesh(const TriangleMesh& mesh, const Dims& dims,
                                      PrismHeight height, const Progress& progress) {
  SM_ASSIGN_OR_RETURN(VoxelSet model, VoxelizePrisms(mesh, dims, height, progress));
  if (mesh.body_pieces.empty()) return model;
  TriangleMesh body;
  body.vertices = mesh.vertices;
  for (const int32_t piece : mesh.body_pieces) {
    body.faces.clear();
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      if (mesh.face_piece[f] == piece) body.faces.push_back(mesh.faces[f]);
    }
    SM_ASSIGN_OR_RETURN(VoxelSet inside, VoxelizeClosedSurface(body, dims));
    model = Union(model, inside);
  }
  return model;
}

}  // namespace sheetmesh
