// Junctions of the mid-surface's charts (beyond the paper; ALGORITHM "Junctions as curves"):
// where two sheets meet — charts whose voxels touch, or touch one component of the voxels
// left between them (a separation's cut, two layers' merge) — the junction is the line where
// their planes fitted near the contact cross. Each chart that ends there is cut at the line
// and filled up to it on its plane, and the charts share the line's vertices, so that the
// mesh meets along one straight polyline at the angle the planes make. A chart the line runs
// through is split there: pieces split at every crossing.
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_JUNCTIONS_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_JUNCTIONS_H_

#include <cstdint>
#include <memory>
#include <vector>

#include "common/types.h"
#include "worker/pipeline/surface/mid_surface_chart.h"
#include "worker/pipeline/surface/mid_surface_junction_line.h"

namespace sheetmesh {

// Finds the junctions of `charts` (their voxels, with `loose` the voxels in none) in a box of
// `dims`, cuts and fills the charts there, splits those a line runs through (appending the
// new charts, with piece ids from *next_piece on), and returns the lines.
std::vector<JunctionLine> JoinCharts(std::vector<std::unique_ptr<Chart>>* charts,
                                     const std::vector<Index3>& loose, const Dims& dims,
                                     const JunctionOptions& options, int32_t* next_piece);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_JUNCTIONS_H_
