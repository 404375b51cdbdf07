// `sheetmesh-pipeline surface` and `score`: mesh a volume's sheets (SCVD, triangles,
// similarity, files), and score any mesh file against a volume.
#ifndef SHEETMESH_WORKER_PIPELINE_CLI_SURFACE_COMMAND_H_
#define SHEETMESH_WORKER_PIPELINE_CLI_SURFACE_COMMAND_H_

#include <ostream>
#include <string>

#include "absl/status/status.h"
#include "worker/pipeline/run/pipeline.h"

namespace sheetmesh {

// Runs the pipeline and prints a summary; files and report.json go to options.output.dir.
absl::Status RunSurface(const PipelineOptions& options, std::ostream& out);

// Joins the bricks of the plan in `plan_dir` and runs the plan's job on them (MergeBricks),
// files in `output_dir`; prints what the bricks held and the summary RunSurface prints.
absl::Status RunMergeCommand(const std::string& plan_dir, const std::string& output_dir,
                             std::ostream& out);

// Tetrahedralizes the box of `box` (dims and placement) around the sheets of the surface
// file `surface` (PLY with thickness and piece from `surface`/`run`, or OBJ), writes the
// volume files of options.output and a volume_report.json, and prints a summary.
absl::Status RunVolume(const std::string& surface, const VolumeInfo& box,
                       const PipelineOptions& options, std::ostream& out);

struct ScoreCommandOptions {
  SheetInput input;       // the image
  std::string mesh_path;  // .ply or .obj, physical coordinates of the input
  bool closed = false;    // score by enclosed volume (closed surfaces of other tools);
                          // otherwise as sheet prisms from the PLY's face thickness
  bool hausdorff = true;
  bool json = false;
};

// Scores a mesh file against the volume's sheet phase with the same scorer the pipeline
// uses, and prints the figures.
absl::Status RunScore(const ScoreCommandOptions& options, std::ostream& out);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_CLI_SURFACE_COMMAND_H_
