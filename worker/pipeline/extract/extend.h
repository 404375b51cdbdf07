// Extend: grows a patch along its tangent planes (paper §2.2.2, formula 4, Fig. 5;
// ALGORITHM §6). For a generator Z with unit normal n, a voxel V may be added when
// |v.n| < t and sqrt(|v|^2 - (v.n)^2) < R with v = V - Z: a flat cylinder around Z.
#ifndef SHEETMESH_WORKER_PIPELINE_EXTRACT_EXTEND_H_
#define SHEETMESH_WORKER_PIPELINE_EXTRACT_EXTEND_H_

#include <cstdint>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/voxel/labelled_voxels.h"

namespace sheetmesh {

struct ExtendOptions {
  double half_thickness_voxels = 1.5;  // t in formula 4
  double radius_voxels = 7.0;          // R in formula 4
  int max_rounds = 1;                  // rebuild-and-extend rounds at most
  double scvd_radius_voxels = 5.0;     // r of the SCVD whose triangles give the normals
  uint64_t seed = 1;                   // SCVD seed
  // What one round may cost: the claims it holds at once, and the voxels it looks at. A
  // round estimated beyond either is kResourceExhausted before it starts.
  int64_t memory_bytes = int64_t{4} << 30;
  double max_visits = 4e10;
  // How a round keeps its claims: a sorted list, or the best claim per voxel of the whole
  // image; kAuto takes the smaller. Both give the same patch (the nearest plane's claim,
  // ties to the lower label).
  enum class ClaimStore { kAuto, kList, kDense };
  ClaimStore claims = ClaimStore::kAuto;
  // The list is gathered slab by slab along z, each slab's claims reduced to one per voxel
  // before the next: a slab holds about this many raw claims (cylinders overlap, so what is
  // kept is far less than every cylinder's claims at once).
  int64_t slab_claims = int64_t{1} << 25;
};

struct ExtendResult {
  LabelledVoxels patch;  // the patch with the added voxels, labelled like the generator that
                         // added them
  uint64_t added = 0;
  int rounds = 0;  // rounds that added something
};

struct ScvdOfSet;  // scvd_of_set.h

// Extends `patch`. Detection mode when `within` is null: empty space may be added, so
// fragments lying in one plane bridge (Fig. 6). Recovery mode otherwise: only voxels of
// `within` (the original image) are added (Fig. 7). A voxel two generators could add goes
// to the one whose plane it is nearest. Only cells on the patch's rim extend: elsewhere
// the cylinder lies inside the patch. kInvalidArgument for t, R or r not positive or a
// `within` of other dims; kCancelled if asked.
// With `first_round`, the SCVD the first round was built on is left there (when the patch
// is not empty), for a later step with the same radius and seed. kResourceExhausted, naming t
// and R, when a round's estimated cost (a slab's claims, or the dense store) or the claims it
// keeps pass options.memory_bytes, or its visits max_visits.
absl::StatusOr<ExtendResult> Extend(const LabelledVoxels& patch, const ExtendOptions& options,
                                    const VoxelSet* within = nullptr, const Progress& progress = {},
                                    ScvdOfSet* first_round = nullptr);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_EXTRACT_EXTEND_H_
