// TetMesh: a tetrahedral mesh of the rock block whose sheet triangles are internal faces
// tagged with their piece and thickness (ALGORITHM §10), in physical units. Pieces meshed as
// bodies are regions of their own: their boundary faces are tagged like a sheet's (piece,
// thickness 0) and the tetrahedra inside carry the piece.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_TET_MESH_H_
#define SHEETMESH_WORKER_PIPELINE_TET_TET_MESH_H_

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "common/types.h"
#include "worker/pipeline/mesh/triangle_mesh.h"

namespace sheetmesh {

using Tet = std::array<uint32_t, 4>;

struct TetMesh {
  std::vector<Vec3> nodes;  // physical units
  std::vector<Tet> tets;
  std::vector<std::array<uint32_t, 3>> faces;  // faces on the PLC's facets
  std::vector<int32_t> face_marker;            // per face: 1 = box, >= 10 sheet triangle
  std::vector<int32_t> face_piece;             // per face: sheet piece, -1 on the box
  std::vector<float> face_thickness_voxels;    // per face: sheet thickness (its aperture where
                                               // fitted) in voxels, 0 on the box
  std::vector<int32_t> body_pieces;  // pieces that are bodies, sorted (their faces bound them)
  std::vector<int32_t> tet_region;   // per tetrahedron: the body piece it fills, -1 in the
                                     // rock; empty when there are no bodies
  double voxel_length = 1.0;  // one voxel in physical units: thickness in voxels = physical / it
  std::string unit;           // the length unit of nodes and thickness ("mm"); empty: unknown

  // "lengths in mm (a voxel is 0.005 mm)", or "lengths in voxels" where the unit is unknown
  // and a voxel is 1: what every writer states in its header.
  std::string UnitsText() const;

  // The faces on sheets and bodies' walls as a surface in voxel coordinates (nodes through
  // the inverse of `placement`, thickness in voxels), with the body pieces: what the volume
  // mesh carries of the surface, for scoring it as the surface is scored.
  TriangleMesh SheetSurface(const Placement& placement) const;

  // Face f's thickness in physical units (the unit of the nodes).
  float FaceThickness(size_t f) const {
    return static_cast<float>(face_thickness_voxels[f] * voxel_length);
  }

  // Drops the nodes no tetrahedron or face uses (an improvement's contraction leaves them),
  // numbering the rest in order; returns how many went.
  uint32_t RemoveUnusedNodes();

  size_t num_sheet_faces() const;
  bool IsBody(int32_t piece) const {
    return std::binary_search(body_pieces.begin(), body_pieces.end(), piece);
  }
  // The region of tetrahedron t: a body piece, or -1 (the rock).
  int32_t Region(size_t t) const { return tet_region.empty() ? -1 : tet_region[t]; }
};

// Signed volume of a tetrahedron: ((b - a) x (c - a)) . (d - a) / 6. (These few are inline:
// the improvement pass calls them millions of times.)
inline double TetVolume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return Dot(Cross(b - a, c - a), d - a) / 6.0;
}

// The centre of the sphere through a, b, c and d; false when they are coplanar.
inline bool Circumcentre(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, Vec3* centre) {
  const Vec3 u = b - a, w = c - a, t = d - a;
  const double det = 2 * Dot(u, Cross(w, t));
  if (!(std::abs(det) > 0)) return false;
  *centre = a + (Cross(w, t) * Norm2(u) + Cross(t, u) * Norm2(w) + Cross(u, w) * Norm2(t)) / det;
  return true;
}

// A triangle's vertex ids in increasing order: the same key for every orientation.
using FaceKey = std::array<uint32_t, 3>;
inline FaceKey SortedFace(uint32_t a, uint32_t b, uint32_t c) {
  if (a > b) std::swap(a, b);
  if (b > c) std::swap(b, c);
  if (a > b) std::swap(a, b);
  return {a, b, c};
}
// The face of t opposite its vertex f, as a key.
inline FaceKey TetFace(const Tet& t, int f) {
  return SortedFace(t[(f + 1) % 4], t[(f + 2) % 4], t[(f + 3) % 4]);
}

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_TET_MESH_H_
