// The mid-surface of each sheet piece at voxel resolution, with its aperture (beyond the
// paper, ALGORITHM "Where the paper's surface loses fidelity"): a piece is a height field
// over the plane across its dominant axis — each column of its voxels along that axis gives
// the mid-point of its run and the run's length — meshed with a vertex at every corner of the
// columns' squares, so that the triangles cover each column whole (no band along the rim
// that projects into no face), and a thickness per vertex measured across the sheet (the
// run's length times the cosine of the surface's tilt from the axis). The formula-5 prisms
// of this mesh hold every run's voxels; decimation (aperture_decimate.h) takes it to a
// budget.
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_H_

#include <cstdint>
#include <functional>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "common/types.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/surface/mid_surface_box.h"
#include "worker/pipeline/surface/mid_surface_chart.h"
#include "worker/pipeline/surface/mid_surface_junction_line.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

struct MidSurface {
  // Vertices at the columns' corners (voxel coordinates), two faces per column, oriented
  // towards +axis; vertex_thickness_voxels across the sheet, face_piece, and
  // face_thickness_voxels the mean of each face's corners'.
  TriangleMesh mesh;
  std::vector<MidSurfaceChart> charts;  // one per piece, by piece id
  // Voxels where two layers of a piece merge (a shallow crossing), in no chart: the
  // junction between the pieces its layers became.
  std::vector<Index3> junction_voxels;
  // Where the charts meet: straight lines whose samples are vertices of the mesh, shared by
  // every chart that ends there (mid_surface_junctions.h).
  std::vector<JunctionLine> junctions;
};

// Each face along a junction of `lines` (an edge on a line, the face of a piece that ends
// there) has its other corner put on its piece's plane there, so that the sheets meet at the
// angle of their planes whatever decimation and the vertex fit did near the line. Returns
// the vertices moved. The mesh's vertices, faces and face_piece are read; vertices move.
uint64_t FlattenAtJunctions(TriangleMesh* mesh, const std::vector<JunctionLine>& lines);

// The pieces a mid-surface can mesh: each of `pieces` (a label per voxel of `set`, -1 none)
// whose layers are height fields (95% of its voxels outside junctions in columns of one run
// of their layer) stays as it is; the voxels of the others take the label `separate` gives
// them (separation's pieces, aligned the same way; -1: cut away, a junction), renumbered
// past `pieces`' labels; its pieces under a fiftieth of their component (at least 64
// voxels) are junction too (-1). `separate` is called only when some piece needs it; its errors
// pass through.
absl::StatusOr<std::vector<int32_t>> MidSurfacePieces(
    const VoxelSet& set, std::span<const int32_t> pieces,
    const std::function<absl::StatusOr<std::vector<int32_t>>()>& separate);

// The mid-surface of every piece of `set` (`piece_of_voxel` aligned with the set's voxels;
// empty: each 6-connected component is a piece). Pieces of fewer than 3 voxels give no
// face. kInvalidArgument when the labels do not match the set; kCancelled if asked.
absl::StatusOr<MidSurface> BuildMidSurface(const VoxelSet& set,
                                           std::span<const int32_t> piece_of_voxel,
                                           const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_H_
