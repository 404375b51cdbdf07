// Where a mid-surface meets the box: the mesh clipped to it, its rim settled on the faces.
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_BOX_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_BOX_H_

#include <cstdint>
#include <vector>

#include "common/types.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/surface/mid_surface_junction_line.h"

namespace sheetmesh {

// Per vertex, 1 where it lies on two or more faces of the box of `dims`: where a sheet's
// outline turns from one face to another, a corner no decimation may cut off.
std::vector<uint8_t> OutlineCornersOnBox(const std::vector<Vec3>& vertices, const Dims& dims);

// Clips `mesh` to the box [-0.5, n - 0.5] of `dims` on each axis: a vertex within 0.2 voxel
// of a face's plane is put on it, a triangle across it cut there (its cut's vertices shared
// by the triangles on the edge, their thickness interpolated), the parts outside dropped.
// The vertices left unused go; the lines' sample vertices follow.
void ClipMeshToBox(const Dims& dims, std::vector<JunctionLine>* lines, TriangleMesh* mesh);

// A sheet meets a box face at the angle of its plane, as it meets another sheet: the
// vertices of the mesh's rim within 0.1 voxel of a face of the box of `dims` go onto it, and
// every other vertex within a voxel of a face slides along its sheet (in its tangent plane)
// until it is a voxel off, where the sheet leaves the face at 15 degrees or more and no face
// around it turns over. What decimation and the vertex fit moved near the box would otherwise
// be pressed flat onto the face by the volume mesh's snapping, a sliver wedge where the rock
// has none. Returns the vertices moved.
uint64_t SettleAtBox(const Dims& dims, TriangleMesh* mesh);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_BOX_H_
