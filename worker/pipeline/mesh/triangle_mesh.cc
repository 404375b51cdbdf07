#include "worker/pipeline/mesh/triangle_mesh.h"

#include <algorithm>

#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {

bool TriangleMesh::IsBody(int32_t piece) const {
  return std::binary_search(body_pieces.begin(), body_pieces.end(), piece);
}

bool TriangleMesh::IsBodyFace(size_t f) const {
  return !body_pieces.empty() && f < face_piece.size() && IsBody(face_piece[f]);
}

double MeanEdgeLength(const TriangleMesh& mesh) {
  if (mesh.faces.empty()) return 0.0;
  double sum = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto c = Corners(mesh, f);
    sum += Norm(c[1] - c[0]) + Norm(c[2] - c[1]) + Norm(c[0] - c[2]);
  }
  return sum / (3.0 * mesh.faces.size());
}

double SurfaceArea(const TriangleMesh& mesh) {
  double a = 0;
  for (size_t f = 0; f < mesh.faces.size(); ++f) a += Area(Corners(mesh, f));
  return a;
}

}  // namespace sheetmesh
