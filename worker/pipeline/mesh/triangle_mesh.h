// TriangleMesh: the surface mesh of sheets and bodies — vertices in voxel index
// coordinates, faces, and the per-face attributes the method carries (thickness, piece).
// A sheet is one layer of triangles whose thickness says how thick the piece is there; a
// body (a piece as thick as it is wide) is the closed surface around its voxels, its faces
// of thickness 0.
#ifndef SHEETMESH_WORKER_PIPELINE_MESH_TRIANGLE_MESH_H_
#define SHEETMESH_WORKER_PIPELINE_MESH_TRIANGLE_MESH_H_

#include <array>
#include <cstdint>
#include <vector>

#include "common/types.h"

namespace sheetmesh {

using Face = std::array<uint32_t, 3>;

struct TriangleMesh {
  std::vector<Vec3> vertices;  // voxel index coordinates (not physical)
  std::vector<Face> faces;
  std::vector<float> face_thickness_voxels;  // per face, voxels; empty when not computed
  // Per face, voxels: the opening of the sheet the face belongs to, for a flow model
  // (surface/face_apertures.h); empty when not computed. face_thickness_voxels is the prism height
  // that scores best with its neighbours'.
  std::vector<float> face_aperture_voxels;
  std::vector<int32_t> face_piece;             // per face, object id; empty when not labelled
  std::vector<float> vertex_thickness_voxels;  // per vertex, voxels; empty unless computed
  std::vector<int32_t> body_pieces;  // pieces meshed as bodies, sorted; the rest are sheets

  size_t num_vertices() const { return vertices.size(); }
  size_t num_faces() const { return faces.size(); }
  // Whether `piece` is a body, face `f` one of a body's faces.
  bool IsBody(int32_t piece) const;
  bool IsBodyFace(size_t f) const;
};

// The key of the undirected edge {a, b}: the smaller id in the high half.
inline uint64_t EdgeKey(uint32_t a, uint32_t b) {
  return a < b ? (static_cast<uint64_t>(a) << 32) | b : (static_cast<uint64_t>(b) << 32) | a;
}

// Corners of face `f`.
inline std::array<Vec3, 3> Corners(const TriangleMesh& m, size_t f) {
  return {m.vertices[m.faces[f][0]], m.vertices[m.faces[f][1]], m.vertices[m.faces[f][2]]};
}

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_MESH_TRIANGLE_MESH_H_
