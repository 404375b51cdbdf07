#include "worker/pipeline/extract/separation.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include "absl/container/flat_hash_map.h"
#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "worker/pipeline/extract/scvd_of_set.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/mesh/vertex_normals.h"

namespace sheetmesh {

namespace {

// The eigenvalues, ascending, of the covariance of the positions `ids`.
Eigen::Vector3d CovarianceEigenvalues(std::span<const Vec3> pos, const std::vector<uint32_t>& ids) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (uint32_t z : ids) mean += Eigen::Vector3d(pos[z].x, pos[z].y, pos[z].z);
  mean /= double(ids.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (uint32_t z : ids) {
    const Eigen::Vector3d d = Eigen::Vector3d(pos[z].x, pos[z].y, pos[z].z) - mean;
    cov += d * d.transpose();
  }
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvalues();
}

// sqrt(λ_min / λ_mid) of the covariance of the positions: 0 for points on a plane, about
// tan(φ / 2) for two half-planes folded by φ.
double FoldOfFit(std::span<const Vec3> pos, const std::vector<uint32_t>& ids) {
  if (ids.size() < 4) return 0.0;
  const Eigen::Vector3d l = CovarianceEigenvalues(pos, ids);
  return l(1) > 0 ? std::sqrt(std::max(0.0, l(0)) / l(1)) : 0.0;
}

// The vertices within `rings` edges of `v` (v among them), by breadth-first search.
std::vector<uint32_t> Neighbourhood(const std::vector<std::vector<uint32_t>>& adj, uint32_t v,
                                    int rings) {
  std::vector<uint32_t> out = {v};
  size_t begin = 0;
  for (int k = 0; k < rings; ++k) {
    const size_t end = out.size();
    for (size_t i = begin; i < end; ++i) {
      for (uint32_t u : adj[out[i]]) {
        if (std::find(out.begin(), out.end(), u) == out.end()) out.push_back(u);
      }
    }
    begin = end;
  }
  return out;
}

}  // namespace

std::vector<uint8_t> FlatVertices(std::span<const Vec3> positions, std::span<const Face> faces,
                                  double dihedral_degrees, int fit_rings) {
  std::vector<uint8_t> flat(positions.size(), 1);
  absl::flat_hash_map<uint64_t, std::vector<uint32_t>> edge_faces;
  for (uint32_t f = 0; f < faces.size(); ++f) {
    for (int k = 0; k < 3; ++k)
      edge_faces[EdgeKey(faces[f][k], faces[f][(k + 1) % 3])].push_back(f);
  }
  std::vector<uint8_t> folded(positions.size(), 0);  // at a fold or an edge of 3+ triangles
  for (const auto& [k, fs] : edge_faces) {
    const uint32_t p = static_cast<uint32_t>(k >> 32), q = static_cast<uint32_t>(k);
    bool bent = fs.size() >= 3;  // a crossing, or cells stacked across a thick sheet
    for (size_t i = 0; i < fs.size() && !bent; ++i) {
      for (size_t j = i + 1; j < fs.size() && !bent; ++j) {
        auto third = [&](const Face& f) {
          return f[0] != p && f[0] != q ? f[0] : (f[1] != p && f[1] != q ? f[1] : f[2]);
        };
        bent = DihedralAngleDegrees(positions[p], positions[q], positions[third(faces[fs[i]])],
                                    positions[third(faces[fs[j]])]) < dihedral_degrees;
      }
    }
    if (bent) folded[p] = folded[q] = 1;
  }
  if (fit_rings <= 0) {
    for (size_t v = 0; v < flat.size(); ++v) flat[v] &= !folded[v];
    return flat;
  }
  std::vector<std::vector<uint32_t>> adj(positions.size());
  for (const auto& [k, fs] : edge_faces) {
    const uint32_t p = static_cast<uint32_t>(k >> 32), q = static_cast<uint32_t>(k);
    adj[p].push_back(q);
    adj[q].push_back(p);
  }
  for (std::vector<uint32_t>& ring : adj) std::sort(ring.begin(), ring.end());  // not hash order
  const double most = std::tan((180.0 - dihedral_degrees) / 2 * std::numbers::pi / 180);
  for (uint32_t v = 0; v < flat.size(); ++v) {
    if (folded[v] && flat[v] && FoldOfFit(positions, Neighbourhood(adj, v, fit_rings)) > most) {
      flat[v] = 0;
    }
  }
  return flat;
}

namespace {

// Floods over `ok` generators (restricted to `within` when it is not empty), numbering new
// pieces from *next.
void Flood(const std::vector<std::vector<uint32_t>>& adj, const std::vector<uint8_t>& ok,
           const std::vector<uint8_t>& within, std::vector<int32_t>* piece, int32_t* next) {
  std::vector<uint32_t> stack;
  auto allowed = [&](uint32_t z) { return ok[z] && (within.empty() || within[z]); };
  for (uint32_t z = 0; z < piece->size(); ++z) {
    if ((*piece)[z] >= 0 || !allowed(z)) continue;
    (*piece)[z] = *next;
    stack.push_back(z);
    while (!stack.empty()) {
      const uint32_t v = stack.back();
      stack.pop_back();
      for (uint32_t u : adj[v]) {
        if ((*piece)[u] < 0 && allowed(u)) {
          (*piece)[u] = *next;
          stack.push_back(u);
        }
      }
    }
    ++*next;
  }
}

// 1 - λ_min / λ_mid of the positions' covariance: near 1 for points on a plane.
double Planarity(const std::vector<Vec3>& pos, const std::vector<uint32_t>& ids) {
  if (ids.size() < 4) return 1.0;
  const Eigen::Vector3d l = CovarianceEigenvalues(pos, ids);
  return l(1) > 0 ? 1.0 - l(0) / l(1) : 1.0;
}

absl::Status CheckAngle(const SeparationOptions& options) {
  if (!(options.dihedral_degrees > 0 && options.dihedral_degrees <= 180)) {
    return absl::InvalidArgumentError(absl::StrCat("separation D_ang = ", options.dihedral_degrees,
                                                   " degrees must be in (0, 180]"));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<SeparationResult> Separate(const VoxelSet& set, const SeparationOptions& options,
                                          const Progress& progress) {
  SM_RETURN_IF_ERROR(CheckAngle(options));
  SM_ASSIGN_OR_RETURN(
      ScvdOfSet s, BuildScvdOfSet(set, options.radius_voxels, options.seed, progress.Sub(0, 0.9)));
  return SeparateOver(s, {}, options, progress.Sub(0.9, 1.0));
}

absl::StatusOr<SeparationResult> SeparateOver(const ScvdOfSet& s,
                                              std::span<const uint8_t> cell_in_set,
                                              const SeparationOptions& options,
                                              const Progress& progress) {
  SM_RETURN_IF_ERROR(CheckAngle(options));
  const SheetAnalysis& sheet = s.sheet;
  const Scvd& scvd = s.scvd;
  const std::vector<Vec3>& pos = s.positions;
  auto in_set = [&](uint32_t g) { return cell_in_set.empty() || cell_in_set[g] != 0; };
  std::vector<Face> faces;
  for (const Face& f : s.faces) {
    if (in_set(f[0]) && in_set(f[1]) && in_set(f[2])) faces.push_back(f);
  }
  SeparationResult out;
  std::vector<uint8_t> flat = FlatVertices(pos, faces, options.dihedral_degrees, options.fit_rings);
  for (uint32_t g = 0; g < flat.size(); ++g) {
    if (!in_set(g)) flat[g] = 0;  // outside the set: never flooded, never kept
  }
  std::vector<std::vector<uint32_t>> adj(scvd.num_generators());
  for (const Face& f : faces) {
    for (int k = 0; k < 3; ++k) {
      adj[f[k]].push_back(f[(k + 1) % 3]);
      adj[f[(k + 1) % 3]].push_back(f[k]);
    }
  }
  for (uint32_t g = 0; g < flat.size(); ++g) {
    if (!in_set(g)) continue;
    ++out.generators;
    out.nonflat_generators += flat[g] == 0;
  }

  // Algorithm 2: flood over flat, unmarked generators through mesh edges.
  std::vector<int32_t> piece(scvd.num_generators(), -1);
  int32_t next = 0;
  Flood(adj, flat, {}, &piece, &next);

  // One missed cell along a crossing lets a flood pass from one sheet into another; such a
  // piece is not planar. Those pieces are flooded again with the non-flat set widened, and
  // the widening ring then rejoins the piece most of its neighbours belong to, so the cut
  // stays as narrow as Algorithm 2's.
  if (options.widen_rings > 0) {
    std::vector<uint8_t> suspect(next, 0);
    std::vector<std::vector<uint32_t>> members(next);
    for (uint32_t z = 0; z < piece.size(); ++z) {
      if (piece[z] >= 0) members[piece[z]].push_back(z);
    }
    for (int32_t p = 0; p < next; ++p) {
      bool touches = false;
      for (uint32_t z : members[p]) {
        for (uint32_t u : adj[z]) touches |= !flat[u];
      }
      suspect[p] = touches && Planarity(pos, members[p]) < options.planarity_threshold;
    }
    std::vector<uint8_t> narrowed = flat;  // flat, outside the widening of suspect pieces
    std::vector<uint8_t> redo(piece.size(), 0);
    for (uint32_t z = 0; z < piece.size(); ++z) redo[z] = piece[z] >= 0 && suspect[piece[z]];
    for (int ring = 0; ring < options.widen_rings; ++ring) {
      std::vector<uint8_t> step = narrowed;
      for (uint32_t z = 0; z < narrowed.size(); ++z) {
        if (narrowed[z]) continue;
        for (uint32_t u : adj[z]) {
          if (redo[u]) step[u] = 0;
        }
      }
      narrowed.swap(step);
    }
    for (uint32_t z = 0; z < piece.size(); ++z) {
      if (redo[z]) piece[z] = -1;
    }
    Flood(adj, narrowed, redo, &piece, &next);
    for (int ring = 0; ring < options.widen_rings; ++ring) {
      std::vector<int32_t> joined = piece;
      for (uint32_t z = 0; z < piece.size(); ++z) {
        if (piece[z] >= 0 || !flat[z] || !redo[z]) continue;
        std::map<int32_t, int> votes;
        for (uint32_t u : adj[z]) {
          if (piece[u] >= 0) ++votes[piece[u]];
        }
        int best = 0;
        for (const auto& [p, n] : votes) {
          if (n > best) {
            best = n;
            joined[z] = p;
          }
        }
      }
      piece.swap(joined);
    }
  }
  // Voxels of non-flat cells are removed; the rest take their cell's piece.
  std::vector<uint8_t> keep(sheet.set.size());
  for (size_t v = 0; v < keep.size(); ++v) keep[v] = piece[scvd.cell[v]] >= 0;
  out.pieces.set = sheet.set.Filter(keep);
  for (size_t v = 0; v < keep.size(); ++v) {
    if (keep[v]) out.pieces.label.push_back(piece[scvd.cell[v]]);
  }
  uint64_t set_voxels = 0;
  for (size_t v = 0; v < keep.size(); ++v)
    set_voxels += scvd.cell[v] < flat.size() && in_set(scvd.cell[v]);
  out.removed_voxels = set_voxels - out.pieces.set.size();
  // The cells, for recovery to grow from without building another SCVD. (Normals from the
  // kept cells' triangles alone were tried: they lost voxels and similarity on the presets.)
  out.cells.normal = VertexNormals(pos, faces);
  out.cells.thickest.assign(scvd.num_generators(), 0);
  out.cells.cell_of_voxel.reserve(out.pieces.set.size());
  for (size_t v = 0; v < keep.size(); ++v) {
    const uint32_t c = scvd.cell[v];
    if (c < out.cells.thickest.size()) {
      out.cells.thickest[c] = std::max(out.cells.thickest[c], sheet.thickness[v]);
    }
    if (keep[v]) out.cells.cell_of_voxel.push_back(c);
  }
  out.cells.centroid = std::move(scvd.centroid);
  out.pieces.RelabelBySize();
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return out;
}

}  // namespace sheetmesh
