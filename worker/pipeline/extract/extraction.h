// Feature extraction (paper §2.2, Figs. 3 and 11; ALGORITHM §7): refine, detect potential
// objects, separate crossings, remove minor pieces, recover what separation cut. The
// result, labelled by piece, is the model the surface is meshed from.
#ifndef SHEETMESH_WORKER_PIPELINE_EXTRACT_EXTRACTION_H_
#define SHEETMESH_WORKER_PIPELINE_EXTRACT_EXTRACTION_H_

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/extract/extend.h"
#include "worker/pipeline/extract/separation.h"
#include "worker/pipeline/voxel/labelled_voxels.h"

namespace sheetmesh {

struct ExtractionOptions {
  bool refine = true;           // 1. closing then opening (§2.2.1's refinement by t)
  int refine_close_radius = 1;  //    closing radius, voxels (0: none)
  int refine_open_radius = 0;   //    opening radius, voxels (0: none; it would erase
                                //    sheets thinner than twice the radius)
  bool detect = true;           // 2. extend (detection mode); objects = components
  ExtendOptions detect_extend = {1.5, 7.0, 1, 0.0, 1};  // t, R, rounds, r, seed (r 0:
                                                        // separation.radius_voxels)
  uint64_t min_object_voxels = 0;  // M: an object (detect) or piece (remove minor) with
                                   // fewer voxels goes; 0 = three cells of the separation
                                   // SCVD, 3 t̄ (1 + 2 r (r - 1)): too small for a triangle
  bool separate = true;            // 3. Algorithm 2
  SeparationOptions separation;    //    r = 5, D_ang = 150
  bool remove_minor = true;        // 4. pieces below M go
  bool recover = true;             // 5. extend (recovery mode) within the refined input
  ExtendOptions recover_extend = {1.5, 7.0, 10, 0.0, 1};  // r 0: separation.radius_voxels
};

// What one step changed.
struct ExtractionStep {
  std::string name;  // refine, detect, separate, remove_minor, recover
  bool ran = false;  // false: disabled
  uint64_t voxels_before = 0;
  uint64_t voxels_after = 0;
  uint64_t added = 0;
  uint64_t removed = 0;
  uint32_t objects_before = 0;  // components (refine, detect) or labels
  uint32_t objects_after = 0;
  double seconds = 0;

  // The step's figures by name, for the report.
  nlohmann::json Fields() const;
};

// What the workflow did, for the report.
struct ExtractionSummary {
  std::vector<ExtractionStep> steps;
  uint64_t min_object_voxels = 0;  // M as used
  uint64_t model_voxels = 0;       // voxels of the model
  uint32_t pieces = 0;             // its labels

  // The steps and figures by name.
  nlohmann::json Fields() const;
};

struct ExtractionResult : ExtractionSummary {
  LabelledVoxels model;  // pieces labelled 0, 1, ... largest first
};

// Runs the workflow on the sheet phase `input`. kInvalidArgument for bad parameters or
// when nothing survives; errors of the steps pass through; kCancelled if asked.
absl::StatusOr<ExtractionResult> ExtractFeatures(const VoxelSet& input,
                                                 const ExtractionOptions& options,
                                                 const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_EXTRACT_EXTRACTION_H_
