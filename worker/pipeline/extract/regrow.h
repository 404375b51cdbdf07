// Regrow: recovery-mode extension (paper §2.2.2, Fig. 7) as a front that grows until nothing
// is added. Every cell of the patch's SCVD gives a plane — its centroid, the normal of its
// triangles (formula 4's n) and a half-thickness that follows the sheet there: the larger
// of t and half the thickest run through the cell, plus half a voxel. A voxel of `within`
// that the patch lacks joins when a face, edge or corner neighbour already belongs and it
// lies within that neighbour's plane's half-thickness; where several planes reach it, the
// nearest wins (the cut voxels of a crossing go back to the sheet they lie nearer), and it
// carries that plane on. The SCVD is built once; each round looks only at the voxels next
// to the last round's.
#ifndef SHEETMESH_WORKER_PIPELINE_EXTRACT_REGROW_H_
#define SHEETMESH_WORKER_PIPELINE_EXTRACT_REGROW_H_

#include <cstdint>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/extract/cell_planes.h"
#include "worker/pipeline/extract/extend.h"
#include "worker/pipeline/voxel/labelled_voxels.h"

namespace sheetmesh {

// Regrows `patch` within `within` (same dims). options.half_thickness_voxels is the least
// half-thickness, options.scvd_radius_voxels and seed the SCVD's; options.max_rounds caps
// the rounds (0: until nothing is added); radius_voxels is unused (the front moves a voxel
// per round). The result's rounds counts the rounds that added voxels.
// kInvalidArgument for t or r not positive or other dims; kCancelled if asked.
// With `known` (cells of an SCVD already built over a set the patch is made of whole cells
// of, as separation's), no SCVD is built: those cells give the planes.
absl::StatusOr<ExtendResult> Regrow(const LabelledVoxels& patch, const ExtendOptions& options,
                                    const VoxelSet& within, const CellPlanes* known = nullptr,
                                    const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_EXTRACT_REGROW_H_
