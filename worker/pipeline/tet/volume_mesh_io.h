// Volume mesh files: VTU for ParaView and OpenGeoSys (tetrahedra and the tagged sheet and
// boundary triangles, integer MaterialIDs), Gmsh MSH 4.1 with physical groups and the
// thickness as element data, Abaqus/CalculiX INP with sections and materials (abaqus_io.cc),
// and Exodus II (exodus_io.cc) for MOOSE; the last two also split along the sheets. Each file
// appears atomically. Thickness is physical everywhere, with the voxel value beside it where the
// format has room.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESH_IO_H_
#define SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESH_IO_H_

#include <array>
#include <map>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "worker/pipeline/tet/split_mesh.h"
#include "worker/pipeline/tet/tet_mesh.h"

namespace sheetmesh {

// Cells: tetrahedra (VTK 10) then triangles (VTK 5). Cell data: kind (0 tetrahedron,
// 1 sheet face, 2 boundary face, 3 a body's wall), piece (-1 where none; on a tetrahedron
// the body it fills), MaterialIDs (0 rock, 1 + p for piece p — a body's tetrahedra and
// walls, a sheet's faces — and 1 + the largest piece + 1 for the box faces), thickness (physical)
// and thickness_voxels, aperture (= thickness), permeability a^2/12 and transmissivity a^3/12 (the
// cubic law, physical units; 0 off the sheets).
// `fields`, when given, adds its node scalars as point data and its cell vectors (one per
// tetrahedron, then per face) as cell data.
struct VolumeFields {
  std::vector<std::pair<std::string, std::vector<double>>> node_scalars;
  std::vector<std::pair<std::string, std::vector<Vec3>>> cell_vectors;
};
absl::Status WriteVtu(const std::string& path, const TetMesh& mesh,
                      const VolumeFields* fields = nullptr);

// ASCII MSH 4.1. Physical groups: 3D "rock" (tag 1) and "body_<p>" (tag 100 + p) for every
// body; 2D "boundary" (tag 2), "sheet_<p>" and "body_<p>_wall" (tag 100 + p) for every piece.
// $ElementData "thickness" (physical) and "thickness_voxels" on the sheet triangles.
absl::Status WriteGmsh(const std::string& path, const TetMesh& mesh);

// Abaqus/CalculiX input: *NODE, *ELEMENT TYPE=C3D4 ELSET=ROCK (and ELSET=BODY_<p> for each
// body's tetrahedra), the sheet faces as S3 elements in ELSET=SHEET_<p>, node sets
// BOX_XMIN … BOX_ZMAX (and BOX), *SURFACE definitions (SURF_SHEET_<p>, SURF_BODY_<p>,
// SURF_BOUNDARY) on the faces of the adjacent tetrahedra, materials ROCK, FRACTURE and FILL
// (placeholder elastic constants, to be replaced), a *SOLID SECTION for the rock and each
// body and a *SHELL SECTION per sheet with the piece's mean
// thickness (physical). Ready for a step (*STEP … *END STEP) appended or *INCLUDEd.
absl::Status WriteAbaqus(const std::string& path, const TetMesh& mesh);

// The mesh split along its sheets (split_mesh.h) as an Abaqus/CalculiX input: the tetrahedra
// on the split nodes, node sets SHEET_<p>_NEG and SHEET_<p>_POS and element-face surfaces
// SURF_SHEET_<p>_NEG and SURF_SHEET_<p>_POS on the two sides of each sheet, the box's node
// sets and the materials as WriteAbaqus. For Abaqus (`calculix` false) each sheet face is a
// zero-thickness COH3D6 element in ELSET=SHEET_<p> (nodes 1–3 on the neg side, 4–6 on the
// pos side: its thickness direction is the face's normal) with a *COHESIVE SECTION and a
// placeholder traction-separation stiffness; faces with no node copied (closed at the rim) are
// left out. CalculiX has no cohesive element: there the two sides are a *CONTACT PAIR per
// sheet (surface to surface, a linear pressure-overclosure law) that lets them open and stops
// them passing through each other.
absl::Status WriteSplitAbaqus(const std::string& path, const SplitMesh& split, bool calculix);

// Exodus II: element blocks "rock" (TETRA, 4 nodes, id 1; meshio 5 maps no TETRA4),
// "body_<p>" (TETRA, id 100 + p) and "sheet_<p>" (TRI3, id 100 + p), side sets box_xmin … box_zmax
// (ids 1–6) on the tetrahedra, node sets the same, element variables aperture, permeability and
// transmissivity (0 on the rock).
absl::Status WriteExodus(const std::string& path, const TetMesh& mesh);

// The split mesh as Exodus II for MOOSE: as WriteExodus (each sheet's TRI3 block on its neg
// side's nodes), with side sets sheet_<p>_neg and sheet_<p>_pos (ids 1000 + 2p and
// 1001 + 2p) on the tetrahedra's faces on either side of each sheet, ready for a contact or
// interface condition between them.
absl::Status WriteSplitExodus(const std::string& path, const SplitMesh& split);

// Per face, which side of the mesh's bounding box it lies on (0 x min, 1 x max, 2 y min,
// … 5 z max), or -1 (a sheet face, or a face off the box).
std::vector<int> BoxSides(const TetMesh& mesh);

// The faces grouped by piece: -1 the box, p the faces of piece p (a sheet or a body's wall).
std::map<int32_t, std::vector<size_t>> FaceGroups(const TetMesh& mesh);

// The sheet faces grouped by piece (the box faces, piece -1, and the bodies' walls left
// out).
std::map<int32_t, std::vector<size_t>> SheetFacesByPiece(const TetMesh& mesh);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_VOLUME_MESH_IO_H_
