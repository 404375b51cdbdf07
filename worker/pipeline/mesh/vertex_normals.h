// Vertex normals of possibly unoriented meshes: the mean of the incident faces' unit
// normals, each flipped to agree with the first (ALGORITHM §6).
#ifndef SHEETMESH_WORKER_PIPELINE_MESH_VERTEX_NORMALS_H_
#define SHEETMESH_WORKER_PIPELINE_MESH_VERTEX_NORMALS_H_

#include <span>
#include <vector>

#include "worker/pipeline/mesh/triangle_mesh.h"

namespace sheetmesh {

// One unit normal per position; the zero vector for positions no face uses.
std::vector<Vec3> VertexNormals(std::span<const Vec3> positions, std::span<const Face> faces);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_MESH_VERTEX_NORMALS_H_
