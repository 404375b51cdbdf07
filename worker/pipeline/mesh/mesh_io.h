// Surface mesh files: ASCII PLY with face properties thickness and piece, VTP for
// ParaView with the same attributes, OBJ grouped by piece; coordinates in physical units.
// Readers for PLY and OBJ, so that other tools' meshes can be scored.
#ifndef SHEETMESH_WORKER_PIPELINE_MESH_MESH_IO_H_
#define SHEETMESH_WORKER_PIPELINE_MESH_MESH_IO_H_

#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "common/types.h"
#include "worker/pipeline/mesh/triangle_mesh.h"

namespace sheetmesh {

// Thickness in physical units: voxels times the geometric mean of the spacing (exact for
// isotropic voxels).
double PhysicalLength(double voxels, const Placement& placement);

// ASCII PLY (meshio 5's binary PLY reader takes no face properties; its ASCII one does).
// Vertices x, y, z (physical) and, when present, thickness; faces vertex_indices, thickness
// (physical), thickness_voxels, piece, body (1 on a body's faces, and on its vertices; only
// when the mesh has bodies), and red/green/blue from the thickness for readers
// that keep only colours (VTK's). The file appears atomically.
absl::Status WritePly(const std::string& path, const TriangleMesh& mesh,
                      const Placement& placement);
// VTK XML PolyData (.vtp) with cell data thickness, thickness_voxels, piece, body and point data
// thickness. Atomic.
absl::Status WriteVtp(const std::string& path, const TriangleMesh& mesh,
                      const Placement& placement);
// The same as an UnstructuredGrid of triangles (.vtu), for readers without PolyData
// (meshio): cell data thickness, thickness_voxels, piece, body.
absl::Status WriteSurfaceVtu(const std::string& path, const TriangleMesh& mesh,
                             const Placement& placement);

// Wavefront OBJ, faces grouped by piece ("g piece_3"); the vertex thickness as texture
// coordinates "vt PHYSICAL VOXELS" (OBJ has no per-face values). Atomic.
absl::Status WriteObj(const std::string& path, const TriangleMesh& mesh,
                      const Placement& placement);

// Reads a PLY (ascii or binary, any endianness) or OBJ surface and maps its physical
// coordinates back to voxel index coordinates with `placement`. Polygons are fanned into
// triangles. kInvalidArgument naming the file and the element or line that is malformed;
// kNotFound for a missing file.
absl::StatusOr<TriangleMesh> ReadMesh(const std::string& path, const Placement& placement = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_MESH_MESH_IO_H_
