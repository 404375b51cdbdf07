// Feature extraction (paper §2.2, Figs. 3 and 11; ALGORITHM §7): refine, detect potential
// objects, separate crossings, remove minor pieces, recover what separation cut. The
// result, labelled by piece, is the model the surface is meshed from.
#ifndef SHEETMESH_WORKER_PIPELINE_EXTRACT_EXTRACTION_H_
#define SHEETMESH_WORKER_PIPELINE_EXTRACT_EXTRACTION_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/extract/extend.h"
#include "worker/pipeline/extract/separation.h"
#include "worker/pipeline/voxel/labelled_voxels.h"

namespace sheetmesh {

struct ExtractionOptions {
  bool refine = true;           // 1. closing then opening (§2.2.1's refinement by t)
  int refine_close_radius = 0;  //    closing radius, voxels (0: none; a closing adds voxels
                                //    the image does not have, and at any thickness measured
                                //    it lowered the similarity against the raw phase)
  int refine_open_radius = 0;   //    opening radius, voxels (0: none; it would erase
                                //    sheets thinner than twice the radius)
  bool detect = true;           // 2. extend (detection mode); objects = components
  ExtendOptions detect_extend = {0.0, 0.0, 1, 0.0, 1};  // t, R, rounds, r, seed; 0: from
                                                        // separation.radius_voxels (t 0.3 r,
                                                        // R 1.4 r: 1.5 and 7 at r = 5)
  uint64_t min_object_voxels = 0;        // M: an object (detect) or piece (remove minor) with
                                         // fewer voxels goes; 0 = three cells of the separation
                                         // SCVD, 3 t̄ (1 + 2 r (r - 1)): too small for a triangle
  bool separate = true;                  // 3. Algorithm 2
  SeparationOptions separation = {0.0};  // r (0: max(5, t̄ / 2)), D_ang = 150
  bool remove_minor = true;              // 4. pieces below M go
  bool recover = true;                   // 5. extend (recovery mode) within the refined input
  ExtendOptions recover_extend = {1.5, 7.0, 0, 0.0, 1};  // Regrow (regrow.h): t is the least
                                                         // half-thickness, rounds 0: until
                                                         // nothing is added; r 0:
                                                         // separation.radius_voxels
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
  int rounds = 0;  // detect, recover: rounds that added voxels
  double seconds = 0;

  // The step's figures by name, for the report.
  nlohmann::json Fields() const;
};

// Where the voxels of the sheet phase went: each is kept in the model or was dropped by
// exactly one step (the first that lost it for good).
struct ExtractionRetention {
  uint64_t input_voxels = 0;             // the sheet phase
  uint64_t kept = 0;                     // of those, in the model
  uint64_t dropped_by_refine = 0;        // the opening erased them
  uint64_t dropped_specks = 0;           // objects below M at detection (specks, small bits)
  uint64_t dropped_at_crossings = 0;     // cut by separation, not recovered
  uint64_t dropped_minor_pieces = 0;     // pieces below M after separation, not recovered
  std::vector<uint64_t> kept_per_piece;  // by the model's labels

  double fraction_kept() const { return input_voxels ? double(kept) / input_voxels : 0.0; }
  nlohmann::json Fields() const;
};

// A length the workflow used, and where it came from: "set" (the user's value) or the
// rule that derived it from the measured thickness.
struct DerivedValue {
  std::string key;  // the parameter's key: separate.r, M, detect.t, ...
  double value = 0;
  std::string from;
};

// separate.r left at 0 is max(this, t̄ / 2).
inline constexpr double kSeparationRadiusFloor = 5.0;
// detect.t and detect.R left at 0 are these multiples of separate.r (the paper's 1.5 and 7
// at r = 5), so the cylinder reaches past a cell's rim whatever the cell's size.
inline constexpr double kDetectHalfThicknessPerRadius = 0.3;
inline constexpr double kDetectRadiusPerRadius = 1.4;

// What the workflow did, for the report.
struct ExtractionSummary {
  std::vector<DerivedValue> derived;  // the scale-dependent values as used
  std::vector<ExtractionStep> steps;
  ExtractionRetention retention;
  uint64_t min_object_voxels = 0;  // M as used
  uint64_t model_voxels = 0;       // voxels of the model
  uint32_t pieces = 0;             // its labels

  // The steps and figures by name.
  nlohmann::json Fields() const;
};

// The labels of ExtractionResult::dropped: the step that lost each voxel.
// (The label volume writes each as code + 1: 1 refine, 2 specks, 3 crossings, 4 minor pieces.)
enum class DroppedBy : int32_t { kRefine = 0, kSpeck = 1, kCrossing = 2, kMinorPiece = 3 };

struct ExtractionResult : ExtractionSummary {
  LabelledVoxels model;    // pieces labelled 0, 1, ... largest first
  LabelledVoxels dropped;  // the input's voxels not in the model, labelled by DroppedBy
};

// Runs the workflow on the sheet phase `input`. kInvalidArgument for bad parameters or
// when nothing survives; errors of the steps pass through; kCancelled if asked.
absl::StatusOr<ExtractionResult> ExtractFeatures(const VoxelSet& input,
                                                 const ExtractionOptions& options,
                                                 const Progress& progress = {});

// An extension's options with an SCVD radius of 0 following the separation's (detect.scvd_r
// and recover.scvd_r of 0 take separate.r): the one place that rule lives.
ExtendOptions Following(ExtendOptions extend, const SeparationOptions& separation);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_EXTRACT_EXTRACTION_H_
