// Volume mesh files: VTU for ParaView (tetrahedra and the tagged sheet and boundary
// triangles), Gmsh MSH 4.1 with physical groups (the rock, each sheet piece, the outer
// boundary), Abaqus INP with element and surface sets. Each file appears atomically.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESH_IO_H_
#define SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESH_IO_H_

#include <string>

#include "absl/status/status.h"
#include "worker/pipeline/tet/tet_mesh.h"

namespace sheetmesh {

// Cells: tetrahedra (VTK 10) then triangles (VTK 5). Cell data: kind (0 tetrahedron,
// 1 sheet face, 2 boundary face), piece (-1 where none), thickness (physical, 0 where
// none).
absl::Status WriteVtu(const std::string& path, const TetMesh& mesh);

// ASCII MSH 4.1. Physical groups: 3D "rock" (tag 1); 2D "boundary" (tag 2) and
// "sheet_<p>" (tag 100 + p) for every sheet piece p.
absl::Status WriteGmsh(const std::string& path, const TetMesh& mesh);

// Abaqus input: *NODE, *ELEMENT TYPE=C3D4 ELSET=ROCK, the sheet faces as S3 elements in
// ELSET=SHEET_<p> and the boundary as S3 in ELSET=BOUNDARY, with *SURFACE definitions
// (SURF_SHEET_<p>, SURF_BOUNDARY) on the faces of the adjacent tetrahedra.
absl::Status WriteAbaqus(const std::string& path, const TetMesh& mesh);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESH_IO_H_
