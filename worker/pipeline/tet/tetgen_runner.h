// The one adapter to TetGen: Debian's `tetgen` program (1.5) run as a child process on a
// .poly in a scratch folder, with a time and a memory limit. TetGen's AGPL code stays out
// of sheetmesh's binaries, and a TetGen crash, hang or refusal becomes a Status instead of
// taking the caller down.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_TETGEN_RUNNER_H_
#define SHEETMESH_WORKER_PIPELINE_TET_TETGEN_RUNNER_H_

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "worker/pipeline/tet/plc.h"
#include "worker/pipeline/tet/tet_mesh.h"

namespace sheetmesh {

struct TetgenOptions {
  std::string program = "tetgen";      // the TetGen executable (looked up on PATH)
  double max_radius_edge_ratio = 1.5;  // -q ratio (TetGen's default is 2.0); 0: no -q
  double min_dihedral_degrees = 10.0;  // -q /angle: the smallest dihedral angle asked for
  double max_volume = 0.0;             // -a, physical units^3; 0: none
  // false (the default): -Y, TetGen adds no point on any facet, so every sheet triangle
  // stays one face; the box's faces must then carry their own points (PlcOptions::
  // seed_box). true: TetGen may split facets while it refines.
  bool steiner_on_sheets = false;
  double time_limit_seconds = 600.0;                // killed beyond this
  uint64_t memory_limit_bytes = uint64_t{8} << 30;  // address-space limit of the child
  std::string scratch_dir;                          // "" = $TMPDIR or /tmp
  bool keep_scratch = false;                        // keep the scratch folder (debugging)
  // Where a PLC TetGen crashed or failed on is copied ("" = nowhere): the input of a bug to
  // report, and of a regression case.
  std::string failed_plc_path;
};

// The TetGen command-line switches for `options` (without the file name).
std::string TetgenSwitches(const TetgenOptions& options);

// Tetrahedralizes `plc`. kDeadlineExceeded when TetGen runs past the time limit;
// kResourceExhausted when it runs out of memory; kInternal when it crashes (naming the
// signal) or exits with an error (with the tail of its output); kNotFound when the program
// is missing; kCancelled (the child is killed) if `progress` asks.
absl::StatusOr<TetMesh> RunTetgen(const Plc& plc, const TetgenOptions& options,
                                  const Progress& progress = {});

// The pairs of facets (indices into plc.facets, smaller first) that TetGen's own check
// (-d, exact predicates) finds cutting through each other: what a crash on a PLC that
// passed sheetmesh's checks is looked for by.
absl::StatusOr<std::vector<std::pair<uint32_t, uint32_t>>> FindFacetIntersections(
    const Plc& plc, const TetgenOptions& options, const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_TETGEN_RUNNER_H_
