#include "worker/pipeline/surface/surface_options.h"

namespace sheetmesh {

SurfaceOptions SurfaceOptions::Paper() {
  SurfaceOptions o;
  o.placement = VertexPlacement::kGenerator;
  o.thickness = ThicknessMeasure::kAxisRuns;
  o.dual.rim = false;
  o.dual.close_cracks = false;
  o.scvd.domain = ScvdDomain::kVoxels;
  o.fit_walls = false;
  o.smooth_iterations = 0;
  return o;
}

}  // namespace sheetmesh
