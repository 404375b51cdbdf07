#include "worker/pipeline/surface/face_apertures.h"

#include <algorithm>
#include <utility>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "common/assert.h"
#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {
namespace {

// The area-weighted median of (value, area) pairs; 0 for none.
double WeightedMedian(std::vector<std::pair<double, double>> values) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  double total = 0;
  for (const auto& [v, a] : values) total += a;
  double run = 0;
  for (const auto& [v, a] : values) {
    run += a;
    if (run >= total / 2) return v;
  }
  return values.back().first;
}

}  // namespace

FaceApertureStats SetFaceApertures(TriangleMesh* mesh, std::span<const float> measured, int rings) {
  TriangleMesh& m = *mesh;
  const size_t nf = m.faces.size();
  SM_ASSERT(m.face_thickness_voxels.size() == nf);
  SM_ASSERT(measured.size() == nf);
  FaceApertureStats stats;
  if (nf == 0) return stats;
  const bool pieces = m.face_piece.size() == nf;
  auto piece = [&](size_t f) { return pieces ? m.face_piece[f] : 0; };

  // Faces by the edges they share; a junction's vertices are those of its edges of 3+ faces.
  absl::flat_hash_map<uint64_t, std::vector<uint32_t>> edge_faces;
  for (uint32_t f = 0; f < nf; ++f) {
    const Face& t = m.faces[f];
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = std::min(t[k], t[(k + 1) % 3]), b = std::max(t[k], t[(k + 1) % 3]);
      edge_faces[uint64_t(a) << 32 | b].push_back(f);
    }
  }
  std::vector<uint8_t> junction_vertex(m.vertices.size(), 0);
  for (const auto& [key, fs] : edge_faces) {
    if (fs.size() >= 3) junction_vertex[key >> 32] = junction_vertex[uint32_t(key)] = 1;
  }
  // What gets its sheet's aperture, and what the sheet's aperture is read from.
  enum Kind : uint8_t { kKeep, kCovered, kJunction, kHole };
  std::vector<uint8_t> kind(nf, kKeep);
  std::vector<double> area(nf);
  for (size_t f = 0; f < nf; ++f) {
    area[f] = Area(Corners(m, f));
    if (!m.body_pieces.empty() && m.IsBodyFace(f)) continue;
    const Face& t = m.faces[f];
    if (junction_vertex[t[0]] || junction_vertex[t[1]] || junction_vertex[t[2]]) {
      kind[f] = kJunction;
      ++stats.junction;
    } else if (m.face_thickness_voxels[f] <= 0) {
      kind[f] = measured[f] > 0 ? kCovered : kHole;
      ++(measured[f] > 0 ? stats.covered : stats.holes);
    }
  }
  // Per piece, the area-weighted median of the faces read from.
  absl::flat_hash_map<int32_t, std::vector<std::pair<double, double>>> by_piece;
  for (size_t f = 0; f < nf; ++f) {
    if (kind[f] == kKeep && m.face_thickness_voxels[f] > 0) {
      by_piece[piece(f)].push_back({m.face_thickness_voxels[f], area[f]});
    }
  }
  absl::flat_hash_map<int32_t, double> piece_median;
  for (auto& [p, values] : by_piece) piece_median[p] = WeightedMedian(std::move(values));

  // Each face to set: a breadth-first walk over the faces of its piece, `rings` rings out.
  std::vector<float> out = m.face_thickness_voxels;
  std::vector<uint32_t> seen_at(nf, UINT32_MAX), front, next;
  for (uint32_t f = 0; f < nf; ++f) {
    if (kind[f] != kCovered && kind[f] != kJunction) continue;
    double sum = 0, weight = 0;
    front.assign(1, f);
    seen_at[f] = f;
    for (int ring = 0; ring < rings && !front.empty(); ++ring) {
      next.clear();
      for (uint32_t g : front) {
        const Face& t = m.faces[g];
        for (int k = 0; k < 3; ++k) {
          const uint32_t a = std::min(t[k], t[(k + 1) % 3]), b = std::max(t[k], t[(k + 1) % 3]);
          for (uint32_t h : edge_faces[uint64_t(a) << 32 | b]) {
            if (seen_at[h] == f || piece(h) != piece(f)) continue;
            seen_at[h] = f;
            next.push_back(h);
            if (kind[h] == kKeep && m.face_thickness_voxels[h] > 0) {
              sum += area[h] * m.face_thickness_voxels[h];
              weight += area[h];
            }
          }
        }
      }
      std::swap(front, next);
    }
    double sheet = weight > 0 ? sum / weight : 0;
    if (sheet <= 0) {
      auto it = piece_median.find(piece(f));
      sheet = it != piece_median.end() ? it->second : 0;
    }
    if (sheet <= 0) sheet = measured[f];
    if (sheet <= 0) continue;
    if (kind[f] == kJunction && m.face_thickness_voxels[f] > sheet) ++stats.junction_lowered;
    if (kind[f] == kJunction && m.face_thickness_voxels[f] < sheet) ++stats.junction_raised;
    out[f] = static_cast<float>(sheet);
  }
  m.face_aperture_voxels = std::move(out);
  return stats;
}

}  // namespace sheetmesh
