// The volume mesh split along its sheets for mechanics: every node on a sheet is copied once
// for each side of the sheets that meet there (two inside a sheet, three at a T junction,
// four where two sheets cross, one — not copied — on the rim where a fracture ends in rock),
// so that the two faces of a fracture can open. Each sheet face becomes an interface: its
// three nodes on the side its normal leaves (neg) and on the side it points to (pos).
#ifndef SHEETMESH_WORKER_PIPELINE_TET_SPLIT_MESH_H_
#define SHEETMESH_WORKER_PIPELINE_TET_SPLIT_MESH_H_

#include <array>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <vector>

#include "absl/status/statusor.h"
#include "worker/pipeline/tet/tet_mesh.h"

namespace sheetmesh {

// One sheet face split in two. The nodes are in the face's order in the unsplit mesh: its
// normal (b − a) × (c − a) points from the neg side to the pos side (the thickness direction
// of a cohesive element whose bottom is neg and top is pos).
struct SheetInterface {
  size_t face = 0;  // the face in the unsplit mesh
  int32_t piece = -1;
  float thickness_voxels = 0;
  std::array<uint32_t, 3> neg{}, pos{};  // node ids in the split mesh
  uint32_t tet_neg = 0, tet_pos = 0;     // the tetrahedra on either side
  // No node copied: all three lie on the rim, the face cannot open.
  bool Closed() const { return neg == pos; }
};

// What the split did, for the report.
struct SplitStats {
  size_t sheet_nodes = 0;    // nodes of the unsplit mesh on a sheet face
  size_t rim_nodes = 0;      // of those, kept single (the tetrahedra around them are one side)
  size_t added_nodes = 0;    // copies made
  size_t interfaces = 0;     // sheet faces split in two
  size_t closed_faces = 0;   // interfaces with no node copied
  size_t unsplit_faces = 0;  // sheet faces without a tetrahedron on each side: left whole
  size_t glued_regions = 0;  // pieces of rock so small that the sheets around them stay
                             // glued to them (fewer than 8 tetrahedra: they would float)
  nlohmann::json Fields() const;
};

struct SplitMesh {
  // The nodes (copies appended after the originals), the tetrahedra on the copies of their
  // side, the box faces and bodies' walls on the copies of the tetrahedron they bound, and each
  // sheet face on its neg side (so writers keep the aperture).
  TetMesh mesh;
  std::vector<uint32_t> parent;  // per node of `mesh`: the node of the unsplit mesh it copies
  std::vector<SheetInterface> interfaces;  // one per sheet face, grouped by piece
  SplitStats stats;
};

// Splits `mesh` along its sheets (not the bodies' walls: a body is a region, not a crack).
// The sides around a node are the tetrahedra that reach each other across faces that are not
// sheet faces. A sheet face without a tetrahedron on each side (on the box's face) is left
// whole and counted in stats.unsplit_faces. kInternal where a face bounds no tetrahedron.
absl::StatusOr<SplitMesh> SplitAlongSheets(const TetMesh& mesh);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_SPLIT_MESH_H_
