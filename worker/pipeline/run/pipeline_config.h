// Pipeline settings from a JSON config file: every parameter of ALGORITHM.md by its name,
// grouped by step. Keys that are absent keep their current value; unknown keys are
// refused so that a typo never silently runs the defaults.
//
//   {"input": {"labels": [255], "window": [lo, hi], "dims": [nx, ny, nz], "dtype": "uint8",
//              "byte_order": "little", "header_bytes": 0, "format": "raw",
//              "spacing": [sx, sy, sz], "origin": [ox, oy, oz], "unit": "um",
//              "mask": "rock.tif", "mask_labels": [1]},
//    "extract": true,
//    "refine": {"enabled": true, "close_radius": 1, "open_radius": 0},
//    "detect": {"enabled": true, "t": 1.5, "R": 7, "rounds": 1, "r": 5},
//    "M": 0,
//    "separate": {"enabled": true, "r": 5, "D_ang": 150},
//    "remove_minor": {"enabled": true},
//    "recover": {"enabled": true, "t": 1.5, "R": 7, "rounds": 10, "r": 5},
//    "surface": {"r": 7, "seed": 1, "generators": 0, "thickness": 0, "lloyd_max_iter": 20,
//                "lloyd_tol": 0.001, "method": "extended", "placement": "centroid",
//                "thickness_measure": "normal", "rim": true, "fold_angle": 50,
//                "domain": "auto"},
//    "radius_search": {"goal": "best" | "target" | "none", "target_similarity": 0.6,
//                      "r_min": 2, "r_max": 0},
//    "similarity": {"model": "face", "hausdorff": true, "grid_rates": [2, 3, 4]},
//    "volume_mesh": {"enabled": false, "radius_edge_ratio": 1.5, "min_dihedral": 10,
//                    "max_volume": 0, "steiner_on_sheets": false, "time_limit_seconds": 600,
//                    "memory_limit_bytes": 8589934592, "tetgen": "tetgen", "repair": false,
//                    "snap_voxels": 0.75, "snap_clear_voxels": 1.5, "wedge_degrees": 12,
//                    "wedge_voxels": 1, "lattice": 0.85},
//    "output": {"formats": ["ply", "vtp", "obj"], "model": true,
//               "volume_formats": ["vtu", "msh", "inp"]}}
#ifndef SHEETMESH_WORKER_PIPELINE_RUN_PIPELINE_CONFIG_H_
#define SHEETMESH_WORKER_PIPELINE_RUN_PIPELINE_CONFIG_H_

#include "absl/status/status.h"
#include "absl/strings/string_view.h"
#include "worker/pipeline/run/pipeline.h"

namespace sheetmesh {

// Applies the JSON `text` to `options`. kInvalidArgument naming `source` (the file), the
// key path and the value for malformed JSON, an unknown key, a value of the wrong type or
// out of range.
absl::Status ApplyPipelineConfig(absl::string_view text, absl::string_view source,
                                 PipelineOptions* options);

// Checks the parameters that the steps would otherwise only refuse late (r > 0, 0 < D_ang
// <= 180, t, R > 0, ...), naming the parameter and its value. kInvalidArgument.
absl::Status ValidatePipelineOptions(const PipelineOptions& options);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_RUN_PIPELINE_CONFIG_H_
