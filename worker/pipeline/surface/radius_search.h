// Choosing r (paper §3, Fig. 13; ALGORITHM §12): similarity against r rises, then falls.
// Search r for the best similarity, or for the largest r — the fewest triangles — that
// still reaches a target similarity (the paper takes 60% as acceptable).
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_RADIUS_SEARCH_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_RADIUS_SEARCH_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <span>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/similarity/mesh_model.h"
#include "worker/pipeline/surface/surface_builder.h"
#include "worker/pipeline/voxel/sheet_analysis.h"

namespace sheetmesh {

enum class RadiusGoal {
  kBestSimilarity,    // the r with the highest similarity
  kTargetSimilarity,  // the largest r whose similarity reaches the target
  kTriangles,         // the r whose mesh has `triangles` triangles, within 5%
};

struct RadiusSearchOptions {
  RadiusGoal goal = RadiusGoal::kBestSimilarity;
  double target_similarity = 0.60;  // kTargetSimilarity: the similarity to reach
  uint64_t triangles = 0;           // kTriangles: the triangle count wanted
  bool decimate = true;             // kTriangles: search r for kOversample times the count
                                    // (the caller decimates to it); below the coarsest r's
                                    // count, the coarsest r
  double min_radius_voxels = 2.0;   // smallest r tried
  double max_radius_voxels = 0.0;   // largest r tried; 0 = a quarter of the largest extent
  int patience = 3;                 // trials past the peak (or below target) before stopping
  PrismHeight height = PrismHeight::kFace;  // the model the similarity is computed on
};

// kTriangles with decimation: the dual mesh is built with this many times the triangles
// wanted, and the flattest of them merged away.
inline constexpr double kOversample = 4.0;

struct RadiusTrial {
  double radius = 0;
  uint64_t triangles = 0;
  double similarity = 0;
  bool scored = false;        // false: counted only (the triangle goal), no similarity
  uint64_t decimated_to = 0;  // > 0: the dual mesh decimated to this many faces
};

struct RadiusChoice {
  double radius = 0;                // the chosen r
  uint64_t decimated_to = 0;        // kTriangles: > 0 when the dual mesh at r is decimated to
                                    // this many faces
  bool target_reached = true;       // kTargetSimilarity: false when no r reached the target (the
                                    // best r is chosen then); kTriangles: false when no r gave
                                    // a count within 5% (the nearest is chosen then)
  std::string message;              // why the target was not reached, for the user
  std::vector<RadiusTrial> trials;  // every r tried, in order of trial

  // chosen_r, target_reached and the trials, for the report.
  nlohmann::json Fields() const;
};

// What the search chose, and the surface it chose, as BuildRequestedSurface would give it
// with `surface` at the chosen r (decimated to `choice.decimated_to` when that is > 0).
struct RadiusSearchResult {
  RadiusChoice choice;
  SurfaceResult surface;
};

// Searches r on `sheet` with the other settings of `surface`, labelling faces with
// `piece_of_voxel` as BuildSurface does. kInvalidArgument for a non-positive or inverted
// radius range, a similarity target outside (0, 1), a triangle target of 0 or below the
// fewest triangles the sheet's outline needs (the count at the largest r, which the message
// names); errors of meshing pass through; kCancelled if asked.
absl::StatusOr<RadiusSearchResult> SearchRadius(const SheetAnalysis& sheet,
                                                const SurfaceOptions& surface,
                                                const RadiusSearchOptions& options,
                                                std::span<const int32_t> piece_of_voxel = {},
                                                const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_RADIUS_SEARCH_H_
