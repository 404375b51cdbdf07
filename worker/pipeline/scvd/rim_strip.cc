#include <algorithm>
#include <cmath>
#include <map>

#include "worker/pipeline/mesh/vertex_normals.h"
#include "worker/pipeline/scvd/dual_triangles_parts.h"
#include "worker/pipeline/scvd/rim_classifier.h"

namespace sheetmesh {
namespace {

// The fraction of the triangle's area whose nearest voxel is a sheet voxel, sampled on a
// grid of about half a voxel.
double SheetCoverage(const VoxelSet& set, const Index3& origin, const Triangle& t) {
  const double longest = std::max({Norm(t[1] - t[0]), Norm(t[2] - t[1]), Norm(t[0] - t[2])});
  const int n = std::max(2, static_cast<int>(std::ceil(longest * 2)));
  int inside = 0, total = 0;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; i + j <= n; ++j) {
      const double u = double(i) / n, v = double(j) / n;
      const Vec3 p = t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v;
      ++total;
      inside += set.Contains(std::llround(p.x) - origin.x, std::llround(p.y) - origin.y,
                             std::llround(p.z) - origin.z);
    }
  }
  return total > 0 ? double(inside) / total : 0.0;
}

}  // namespace

void AddRim(const VoxelSet& set, const NeighborTable& neighbors,
            std::span<const uint16_t> thickness, const Scvd& scvd,
            const DualTriangleOptions& options, std::vector<Vec3>* pos, FaceSelector* selector,
            DualTriangulation* out) {
  const uint32_t num_gen = scvd.num_generators();
  // Boundary edges, directed as their one face walks them.
  std::vector<std::pair<uint32_t, uint32_t>> boundary;
  for (const Face& f : selector->faces()) {
    for (int k = 0; k < 3; ++k) {
      const auto* fs = selector->EdgeFaces(f[k], f[(k + 1) % 3]);
      if (fs != nullptr && fs->size() == 1) boundary.emplace_back(f[k], f[(k + 1) % 3]);
    }
  }
  if (boundary.empty()) return;
  std::vector<uint8_t> on_boundary(num_gen, 0);
  for (const auto& [p, q] : boundary) on_boundary[p] = on_boundary[q] = 1;
  // Normals of the generators (the faces are not oriented yet).
  const std::vector<Vec3> normal =
      VertexNormals(std::span<const Vec3>(pos->data(), num_gen), selector->faces());
  // Rim voxels of the boundary cells.
  const RimClassifier rim(set, options.rim_normal_cos);
  auto is_rim = [&](int32_t x, int32_t y, int32_t z, uint32_t c) {
    return rim.IsRim(x, y, z, normal[c]);
  };
  std::vector<Vec3> sum(num_gen);
  std::vector<double> tau(num_gen, 0.0);
  std::vector<uint32_t> count(num_gen, 0);
  const Vec3 origin = Vec3::Of(options.origin);
  set.ForEachVoxel([&](uint64_t v, int32_t x, int32_t y, int32_t z) {
    const uint32_t c = scvd.cell[v];
    if (c == kNoCell || !on_boundary[c] || !is_rim(x, y, z, c)) return;
    sum[c] += Vec3(x, y, z) + origin;
    tau[c] += thickness[v];
    ++count[c];
  });
  // Each boundary cell's rim vertex is the centroid of its outermost rim voxels: those
  // within half a voxel of the farthest along the direction from the generator to all its
  // rim voxels' centroid. A corner cell so reaches its corner, a straight rim keeps the
  // middle of the cell's stretch.
  std::vector<Vec3> centroid(num_gen), outward(num_gen);
  std::vector<double> best_out(num_gen, -1e300);
  for (uint32_t g = 0; g < num_gen; ++g) {
    if (count[g] == 0) continue;
    centroid[g] = sum[g] / count[g];
    Vec3 u = centroid[g] - (*pos)[g];
    u -= normal[g] * Dot(u, normal[g]);
    outward[g] = Normalized(u);
  }
  auto for_each_rim = [&](auto&& f) {
    set.ForEachVoxel([&](uint64_t v, int32_t x, int32_t y, int32_t z) {
      const uint32_t c = scvd.cell[v];
      if (c == kNoCell || !on_boundary[c] || count[c] == 0 || !is_rim(x, y, z, c)) {
        return;
      }
      f(c, Vec3(x, y, z) + origin);
    });
  };
  for_each_rim([&](uint32_t c, const Vec3& p) {
    best_out[c] = std::max(best_out[c], Dot(p - (*pos)[c], outward[c]));
  });
  std::vector<Vec3> outer_sum(num_gen);
  std::vector<uint32_t> outer_count(num_gen, 0);
  for_each_rim([&](uint32_t c, const Vec3& p) {
    if (Dot(p - (*pos)[c], outward[c]) >= best_out[c] - 0.5) {
      outer_sum[c] += p;
      ++outer_count[c];
    }
  });
  std::vector<uint32_t> rim_id(num_gen, UINT32_MAX);
  for (uint32_t g = 0; g < num_gen; ++g) {
    if (outer_count[g] == 0) continue;
    // Along the sheet: the outermost layer; across it: the depth of all the cell's rim
    // voxels, which span the thickness, so the vertex is at mid-depth even where the
    // outermost layer holds a few voxels on one wall.
    Vec3 q = outer_sum[g] / outer_count[g];
    q -= normal[g] * Dot(q - centroid[g], normal[g]);
    if (Norm2(q - (*pos)[g]) < 0.25) continue;  // the generator already sits on the rim
    // The voxels' edge, not their centres: half a voxel further out, so that prisms on
    // the strip hold the outermost layer where the outline runs between voxel centres.
    // Not past the image's outermost voxel centres: where a sheet runs out of the image
    // its outline is the image's edge, and the volume mesh's box face lies there.
    const Vec3 pushed = q + outward[g] * options.rim_push_voxels;
    const Dims image = options.image.num_voxels() > 0 ? options.image : set.dims();
    const double extent[3] = {double(image.nx - 1), double(image.ny - 1), double(image.nz - 1)};
    for (int k = 0; k < 3; ++k) {
      const bool leaves = pushed[k] < 0 || pushed[k] > extent[k];
      q[k] = leaves ? std::clamp(q[k], 0.0, extent[k]) : pushed[k];
    }
    rim_id[g] = static_cast<uint32_t>(pos->size());
    pos->push_back(q);
    out->rim_positions.push_back(q);
    out->rim_cell.push_back(g);
    out->rim_thickness.push_back(static_cast<float>(tau[g] / count[g]));
  }
  out->stats.rim_vertices = out->rim_positions.size();
  // The strip: for boundary edge p -> q, the quad q, p, Q_p, Q_q as two triangles walking
  // the edge as q -> p, so that orientation can agree with the face inside.
  for (const auto& [p, q] : boundary) {
    const uint32_t qp = rim_id[p], qq = rim_id[q];
    std::vector<Face> strip;
    if (qp != UINT32_MAX && qq != UINT32_MAX) {
      strip = {{q, p, qp}, {q, qp, qq}};
    } else if (qp != UINT32_MAX) {
      strip = {{q, p, qp}};
    } else if (qq != UINT32_MAX) {
      strip = {{q, p, qq}};
    }
    for (const Face& f : strip) {
      const FaceSelector::Verdict v = selector->TryAdd(f);
      Count(v, &out->stats);
      if (v == FaceSelector::Verdict::kKept) {
        ++out->stats.rim_faces;
        out->votes.push_back(0);
      }
    }
  }
}

void CloseCracks(const VoxelSet& set, const DualTriangleOptions& options,
                 const std::vector<Vec3>& pos, FaceSelector* selector, DualTriangulation* out) {
  double edge_sum = 0;
  size_t edges = 0;
  for (const Face& f : selector->faces()) {
    for (int k = 0; k < 3; ++k) {
      edge_sum += Norm(pos[f[k]] - pos[f[(k + 1) % 3]]);
      ++edges;
    }
  }
  if (edges == 0) return;
  const double max_edge =
      options.crack_max_edge_voxels > 0 ? options.crack_max_edge_voxels : 1.5 * edge_sum / edges;
  for (int pass = 0; pass < 4; ++pass) {
    // Boundary edges, directed as their one face walks them; the loop continues at the
    // edge leaving the end vertex.
    std::map<uint32_t, std::vector<uint32_t>> next;  // vertex -> boundary successors
    std::map<uint32_t, std::vector<uint32_t>> prev;
    for (const Face& f : selector->faces()) {
      for (int k = 0; k < 3; ++k) {
        const auto* fs = selector->EdgeFaces(f[k], f[(k + 1) % 3]);
        if (fs != nullptr && fs->size() == 1) {
          next[f[k]].push_back(f[(k + 1) % 3]);
          prev[f[(k + 1) % 3]].push_back(f[k]);
        }
      }
    }
    uint64_t closed = 0;
    for (const auto& [v, succ] : next) {
      // Only plain boundary vertices: one edge in, one edge out.
      if (succ.size() != 1 || prev[v].size() != 1) continue;
      const uint32_t w = succ[0], u = prev[v][0];
      if (u == w) continue;
      const Vec3 a = pos[u] - pos[v], b = pos[w] - pos[v];
      const double angle =
          std::acos(std::clamp(Dot(a, b) / (Norm(a) * Norm(b)), -1.0, 1.0)) * 180.0 / M_PI;
      if (angle >= options.crack_angle_degrees || Norm(pos[w] - pos[u]) > max_edge) continue;
      // The boundary runs u -> v -> w inside faces; the ear walks the edges the other way.
      const Face ear = {w, v, u};
      if (SheetCoverage(set, options.origin, {pos[u], pos[v], pos[w]}) < 0.5) continue;
      if (selector->TryAdd(ear) == FaceSelector::Verdict::kKept) {
        ++closed;
        ++out->stats.crack_faces;
        ++out->stats.kept;
        out->votes.push_back(0);
      }
    }
    if (closed == 0) break;
  }
}

}  // namespace sheetmesh
