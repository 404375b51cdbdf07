// ScvdOfSet: a voxel set's analysis, its SCVD and the SCVD's dual triangles (no rim strip):
// what detection's extension, separation's flood and recovery's planes are computed from.
// Built once, it can serve the next step when the radius and seed agree.
#ifndef SHEETMESH_WORKER_PIPELINE_EXTRACT_SCVD_OF_SET_H_
#define SHEETMESH_WORKER_PIPELINE_EXTRACT_SCVD_OF_SET_H_

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/scvd/scvd.h"
#include "worker/pipeline/voxel/sheet_analysis.h"

namespace sheetmesh {

struct ScvdOfSet {
  SheetAnalysis sheet;  // its neighbour table released once the triangles are made
  Scvd scvd;
  std::vector<Vec3> positions;  // the generators'
  std::vector<Face> faces;      // the dual triangles
};

// Builds it with cell radius `radius_voxels` and `seed`. Errors of the analysis, the SCVD
// and the triangulation pass through; kCancelled if asked.
absl::StatusOr<ScvdOfSet> BuildScvdOfSet(VoxelSet set, double radius_voxels, uint64_t seed,
                                         const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_EXTRACT_SCVD_OF_SET_H_
