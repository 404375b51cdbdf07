// PipelineOptions: every setting of one run of the method, stage by stage, with its
// default. The parameter table (parameters.h) names each; RunPipeline (pipeline.h) runs them.
#ifndef SHEETMESH_WORKER_PIPELINE_RUN_PIPELINE_OPTIONS_H_
#define SHEETMESH_WORKER_PIPELINE_RUN_PIPELINE_OPTIONS_H_

#include <string>
#include <vector>

#include "worker/pipeline/extract/extraction.h"
#include "worker/pipeline/flow/permeability.h"
#include "worker/pipeline/similarity/mesh_model.h"
#include "worker/pipeline/surface/radius_search.h"
#include "worker/pipeline/surface/representation.h"
#include "worker/pipeline/surface/surface_builder.h"
#include "worker/pipeline/tet/volume_mesher.h"
#include "worker/pipeline/voxel/sheet_input.h"
#include "worker/pipeline/voxel/sheetness.h"

namespace sheetmesh {

struct ScoreOptions {
  PrismHeight height = PrismHeight::kFace;  // the mesh model of the headline similarity
  bool hausdorff = true;                    // also the symmetric Hausdorff distance
  std::vector<int> grid_rates = {2, 3, 4};  // grid-model baselines of Table 2 (empty: none)
};

// How a dense label volume (one value per voxel of the box) is written.
enum class DenseLabels { kNone, kHdf5, kRaw };

struct OutputOptions {
  std::string dir;          // where files go (created); empty: write nothing
  bool ply = true;          // surface.ply
  bool vtp = true;          // surface.vtp
  bool surface_vtu = true;  // surface.vtu (the same as an unstructured grid)
  bool obj = true;          // surface.obj
  bool model = true;        // with extraction: model.vdb (mask + labels, sparse) and
                            // pieces.csv
  // With extraction: the model's labels as a dense volume the size of the box, written only
  // when asked: model_labels_<dims>.h5 (chunked, compressed) or model_labels_<dims>_u16.raw.
  DenseLabels label_volume = DenseLabels::kNone;
  bool dropped = false;  // with extraction: dropped_labels_<dims>.h5 (or _u16.raw where
                         // label_volume is raw), the voxels of the phase the model lacks
                         // labelled by why (DroppedBy)
  bool vtu = true;       // with a volume mesh: volume.vtu
  bool msh = true;       // volume.msh (Gmsh 4.1)
  bool inp = true;       // volume.inp (Abaqus/CalculiX)
  bool exo = true;       // volume.exo (Exodus II)
  bool previews = true;  // preview_slice_{x,y,z}.png, preview_thickness.png
  bool split = false;    // the volume mesh split along the sheets for mechanics (turns the
                         // volume mesh on): volume_split.inp and volume_split_ccx.inp with
                         // inp, volume_split.exo with exo
};

// Grey levels as the scanner gave them (input.grey): sheets found by their sheetness and
// apertures from the attenuation they miss, instead of a segmented phase.
struct GreyOptions {
  bool enabled = false;
  std::vector<double> levels;     // [void, rock]; empty: measured from the histogram
  double psf_sigma_voxels = 1.0;  // the point spread (Gaussian σ) the apertures' window allows
  SheetnessOptions sheetness;
};

struct PipelineOptions {
  SheetInput input;
  GreyOptions grey;
  bool extract = true;  // run the feature extraction (Fig. 3) first; the surface command: false
  ExtractionOptions extraction;
  SurfaceOptions surface;      // r = surface.scvd.radius_voxels unless searched
  bool search_radius = false;  // choose r with `radius_search`
  RadiusSearchOptions radius_search;
  RepresentationOptions representation;  // each piece a sheet or a body
  ScoreOptions score;
  bool volume_mesh = false;  // tetrahedralize the box with the sheets inside
  VolumeMeshOptions volume;
  FlowOptions flow;  // the sample's permeability tensor on the volume mesh (which it turns on)
  OutputOptions output;
  double time_limit_seconds = 0;  // the run ends kDeadlineExceeded past this (0: none)
};

// Whether the run makes the volume mesh: asked for, or needed by flow.
inline bool MeshesVolume(const PipelineOptions& o) {
  return o.volume_mesh || o.flow.enabled || o.output.split;
}

// Whether a run without the extraction still separates the sheet phase into pieces, as
// stages of its own after "analyze": a mid-surface (surface.mesher midsurface or auto) is a
// height field per piece.
inline bool SeparatesWithoutExtraction(const PipelineOptions& o) {
  return !o.extract && o.surface.method != SurfaceMethod::kScvd && o.extraction.separate;
}

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_RUN_PIPELINE_OPTIONS_H_
