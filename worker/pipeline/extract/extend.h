// Extend: grows a patch along its tangent planes (paper §2.2.2, formula 4, Fig. 5;
// ALGORITHM §6). For a generator Z with unit normal n, a voxel V may be added when
// |v.n| < t and sqrt(|v|^2 - (v.n)^2) < R with v = V - Z: a flat cylinder around Z.
#ifndef SHEETMESH_WORKER_PIPELINE_EXTRACT_EXTEND_H_
#define SHEETMESH_WORKER_PIPELINE_EXTRACT_EXTEND_H_

#include <cstdint>
#include <memory>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "common/types.h"
#include "worker/pipeline/voxel/labelled_voxels.h"

namespace sheetmesh {

struct ExtendOptions {
  double half_thickness_voxels = 1.5;  // t in formula 4
  double radius_voxels = 7.0;          // R in formula 4
  int max_rounds = 1;                  // rebuild-and-extend rounds at most
  double scvd_radius_voxels = 5.0;     // r of the SCVD whose triangles give the normals
  uint64_t seed = 1;                   // SCVD seed
};

struct ExtendResult {
  LabelledVoxels patch;  // the patch with the added voxels, labelled like the generator that
                         // added them
  uint64_t added = 0;
  int rounds = 0;  // rounds that added something
};

struct Scvd;
struct SheetAnalysis;

// Formula 4's normals: the SCVD of a patch (r and seed from `options`) and, per generator,
// the normalised mean normal of its dual triangles (zero for a generator with none).
struct PatchNormals {
  std::unique_ptr<Scvd> scvd;
  std::vector<Vec3> normal;
};
absl::StatusOr<PatchNormals> ComputePatchNormals(const SheetAnalysis& sheet,
                                                 const ExtendOptions& options,
                                                 const Progress& progress = {});

// Extends `patch`. Detection mode when `within` is null: empty space may be added, so
// fragments lying in one plane bridge (Fig. 6). Recovery mode otherwise: only voxels of
// `within` (the original image) are added (Fig. 7). A voxel two generators could add goes
// to the one whose plane it is nearest. Only cells on the patch's rim extend: elsewhere
// the cylinder lies inside the patch. kInvalidArgument for t, R or r not positive or a
// `within` of other dims; kCancelled if asked.
absl::StatusOr<ExtendResult> Extend(const LabelledVoxels& patch, const ExtendOptions& options,
                                    const VoxelSet* within = nullptr,
                                    const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_EXTRACT_EXTEND_H_
