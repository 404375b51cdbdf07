// CellPlanes: the cells of an SCVD over a patch as formula 4 sees them — each cell's
// centroid, the normal of its dual triangles and its thickest run — with the cell of every
// voxel of the patch. Separation builds them; recovery grows from them (regrow.h).
#ifndef SHEETMESH_WORKER_PIPELINE_EXTRACT_CELL_PLANES_H_
#define SHEETMESH_WORKER_PIPELINE_EXTRACT_CELL_PLANES_H_

#include <cstdint>
#include <vector>

#include "common/types.h"

namespace sheetmesh {

struct CellPlanes {
  std::vector<Vec3> centroid;           // per cell
  std::vector<Vec3> normal;             // per cell; zero where the cell has no triangle
  std::vector<uint16_t> thickest;       // per cell: its longest shortest-axis run τ
  std::vector<uint32_t> cell_of_voxel;  // per voxel of the patch, in the patch's order
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_EXTRACT_CELL_PLANES_H_
