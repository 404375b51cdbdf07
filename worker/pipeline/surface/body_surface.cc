#include "worker/pipeline/surface/body_surface.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/strings/str_cat.h"

namespace sheetmesh {
namespace {

// The dual surface of a voxel set (surface nets): one vertex in each cell — the cube whose
// corners are 8 neighbouring voxel centres — that has corners inside and outside, at the
// mean of the midpoints of its edges that cross; one quad around each voxel face between
// an inside voxel and an outside one. Outside the box counts as outside, and a cell that
// reaches past the box has its vertex in the box's face, placed by the crossings inside
// the box: a piece that reaches the box is closed by faces lying exactly in it.
class SurfaceNets {
 public:
  explicit SurfaceNets(const VoxelSet& voxels) : set_(voxels), d_(voxels.dims()) {}

  // The surface, its vertices smoothed `iterations` λ|μ pairs, each kept within its cell
  // (so the voxels stay on their sides of it) and in the box's face where it lies there.
  TriangleMesh Build(int iterations) {
    set_.ForEachVoxel([&](uint64_t, int32_t x, int32_t y, int32_t z) {
      const std::array<int64_t, 3> p = {x, y, z};
      for (int k = 0; k < 3; ++k) {
        for (int side : {-1, 1}) {
          std::array<int64_t, 3> q = p;
          q[k] += side;
          if (!Inside(q)) AddQuad(p, k, side);
        }
      }
    });
    Smooth(iterations);
    return std::move(mesh_);
  }

 private:
  bool Inside(const std::array<int64_t, 3>& p) const { return set_.Contains(p[0], p[1], p[2]); }
  int64_t Extent(int k) const { return k == 0 ? d_.nx : (k == 1 ? d_.ny : d_.nz); }

  // The quad around the face of voxel p towards p + side e_k, its normal pointing there.
  void AddQuad(const std::array<int64_t, 3>& p, int k, int side) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;  // i x j = k
    std::array<uint32_t, 4> v;
    const int di[4] = {-1, 0, 0, -1}, dj[4] = {-1, -1, 0, 0};
    for (int n = 0; n < 4; ++n) {
      std::array<int64_t, 3> c = p;
      if (side < 0) c[k] -= 1;
      c[i] += di[n];
      c[j] += dj[n];
      v[n] = CellVertex(c);
    }
    if (side < 0) std::swap(v[1], v[3]);
    // Cut along the shorter diagonal.
    const Vec3& a = mesh_.vertices[v[0]];
    const Vec3& b = mesh_.vertices[v[1]];
    const Vec3& c = mesh_.vertices[v[2]];
    const Vec3& e = mesh_.vertices[v[3]];
    if (Norm2(a - c) <= Norm2(b - e)) {
      mesh_.faces.push_back({v[0], v[1], v[2]});
      mesh_.faces.push_back({v[0], v[2], v[3]});
    } else {
      mesh_.faces.push_back({v[0], v[1], v[3]});
      mesh_.faces.push_back({v[1], v[2], v[3]});
    }
  }

  // The vertex of the cell with lowest corner c (each coordinate in [-1, n - 1]).
  uint32_t CellVertex(const std::array<int64_t, 3>& c) {
    const uint64_t key = static_cast<uint64_t>(c[0] + 1) +
                         (d_.nx + 1) * (static_cast<uint64_t>(c[1] + 1) +
                                        (d_.ny + 1) * static_cast<uint64_t>(c[2] + 1));
    auto [it, fresh] = cells_.try_emplace(key, static_cast<uint32_t>(mesh_.vertices.size()));
    if (fresh) {
      mesh_.vertices.push_back(Place(c));
      cell_.push_back(c);
    }
    return it->second;
  }

  void Smooth(int iterations) {
    const size_t n = mesh_.vertices.size();
    std::vector<std::vector<uint32_t>> next(n);
    for (const Face& f : mesh_.faces) {
      for (int k = 0; k < 3; ++k) {
        next[f[k]].push_back(f[(k + 1) % 3]);
        next[f[k]].push_back(f[(k + 2) % 3]);
      }
    }
    for (auto& v : next) {
      std::sort(v.begin(), v.end());
      v.erase(std::unique(v.begin(), v.end()), v.end());
    }
    constexpr double kLambda = 0.5, kMu = -0.53;
    std::vector<Vec3> moved(n);
    for (int step = 0; step < 2 * iterations; ++step) {
      const double w = step % 2 == 0 ? kLambda : kMu;
      for (size_t v = 0; v < n; ++v) {
        Vec3 mean;
        for (uint32_t u : next[v]) mean = mean + mesh_.vertices[u];
        const Vec3& p = mesh_.vertices[v];
        Vec3 q = next[v].empty() ? p : p + (mean / double(next[v].size()) - p) * w;
        for (int k = 0; k < 3; ++k) {
          const int64_t c = cell_[v][k];
          // In the box's face where the cell reaches past it; else within the cell.
          q[k] = (c < 0 || c + 1 >= Extent(k)) ? p[k] : std::clamp(q[k], double(c), double(c + 1));
        }
        moved[v] = q;
      }
      mesh_.vertices.swap(moved);
    }
  }

  Vec3 Place(const std::array<int64_t, 3>& c) const {
    bool in[8];
    for (int n = 0; n < 8; ++n) {
      in[n] = Inside({c[0] + (n & 1), c[1] + ((n >> 1) & 1), c[2] + ((n >> 2) & 1)});
    }
    // Which of the cell's corner layers lie in the box, per axis.
    bool low_in[3], high_in[3];
    for (int k = 0; k < 3; ++k) {
      low_in[k] = c[k] >= 0;
      high_in[k] = c[k] + 1 < Extent(k);
    }
    double sum[2][3] = {};
    int count[2] = {0, 0};  // [0]: edges with both ends in the box, [1]: all
    for (int n = 0; n < 8; ++n) {
      for (int k = 0; k < 3; ++k) {
        if ((n >> k) & 1) continue;
        const int m = n | (1 << k);
        if (in[n] == in[m]) continue;
        double mid[3];
        bool in_box = true;
        for (int a = 0; a < 3; ++a) {
          const int bit_n = (n >> a) & 1;
          mid[a] = c[a] + (a == k ? 0.5 : bit_n);
          if (a != k) in_box &= bit_n ? high_in[a] : low_in[a];
        }
        in_box &= low_in[k] && high_in[k];
        for (int t = in_box ? 0 : 1; t < 2; ++t) {
          for (int a = 0; a < 3; ++a) sum[t][a] += mid[a];
          ++count[t];
        }
      }
    }
    const int t = count[0] > 0 ? 0 : 1;
    double p[3];
    for (int a = 0; a < 3; ++a) p[a] = sum[t][a] / count[t];
    for (int k = 0; k < 3; ++k) {
      if (!low_in[k]) p[k] = -0.5;
      if (!high_in[k]) p[k] = Extent(k) - 0.5;
    }
    return Vec3(p[0], p[1], p[2]);
  }

  const VoxelSet& set_;
  const Dims d_;
  TriangleMesh mesh_;
  absl::flat_hash_map<uint64_t, uint32_t> cells_;
  std::vector<std::array<int64_t, 3>> cell_;  // each vertex's cell
};

}  // namespace

absl::StatusOr<BodySurface> MeshBody(const VoxelSet& voxels, int32_t piece, uint64_t triangles) {
  if (voxels.empty()) {
    return absl::InvalidArgumentError(absl::StrCat("piece ", piece, " has no voxels to mesh"));
  }
  BodySurface out;
  // Smoothed within the cells: the staircase of a tilted wall becomes a plane the
  // decimation can merge (without, a rough slab stopped at twice its share of faces).
  constexpr int kSmoothing = 10;
  out.mesh = SurfaceNets(voxels).Build(kSmoothing);
  TriangleMesh& mesh = out.mesh;
  out.faces_before = mesh.faces.size();
  mesh.face_piece.assign(mesh.faces.size(), piece);
  mesh.face_thickness_voxels.assign(mesh.faces.size(), 0.0f);
  if (triangles > 0 && mesh.faces.size() > triangles) {
    DecimateOptions d;
    d.triangles = triangles;
    d.optimal_placement = true;
    d.keep_box = true;
    d.box_lo = Vec3(-0.5, -0.5, -0.5);
    const Dims& n = voxels.dims();
    d.box_hi = Vec3(n.nx - 0.5, n.ny - 0.5, n.nz - 0.5);
    out.decimation = Decimate(&mesh, d);
  }
  mesh.vertex_thickness_voxels.assign(mesh.vertices.size(), 0.0f);
  return out;
}

std::map<int32_t, double> EquivalentApertures(const TriangleMesh& mesh, const Dims& dims) {
  const std::array<double, 3> high = {dims.nx - 0.5, dims.ny - 0.5, dims.nz - 0.5};
  auto on_box = [&](const std::array<Vec3, 3>& t) {
    for (int axis = 0; axis < 3; ++axis) {
      for (const double plane : {-0.5, high[axis]}) {
        if (std::all_of(t.begin(), t.end(),
                        [&](const Vec3& p) { return std::abs((&p.x)[axis] - plane) < 1e-6; })) {
          return true;
        }
      }
    }
    return false;
  };
  std::map<int32_t, std::array<double, 2>> volume_area;
  for (size_t f = 0; f < mesh.faces.size() && f < mesh.face_piece.size(); ++f) {
    const int32_t piece = mesh.face_piece[f];
    if (!mesh.IsBody(piece)) continue;
    const std::array<Vec3, 3> t = Corners(mesh, f);
    auto& [volume, area] = volume_area[piece];
    volume += Dot(t[0], Cross(t[1], t[2])) / 6;
    if (!on_box(t)) area += 0.5 * Norm(Cross(t[1] - t[0], t[2] - t[0]));
  }
  std::map<int32_t, double> out;
  for (const auto& [piece, va] : volume_area) {
    if (va[1] > 0) out[piece] = 2 * std::abs(va[0]) / va[1];
  }
  return out;
}

}  // namespace sheetmesh
