#include "worker/pipeline/mesh/triangle_mesh.h"

#include <algorithm>

namespace sheetmesh {

bool TriangleMesh::IsBody(int32_t piece) const {
  return std::binary_search(body_pieces.begin(), body_pieces.end(), piece);
}

bool TriangleMesh::IsBodyFace(size_t f) const {
  return !body_pieces.empty() && f < face_piece.size() && IsBody(face_piece[f]);
}

}  // namespace sheetmesh
