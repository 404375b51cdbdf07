// Apertures from the grey levels (beyond the paper; the "missing attenuation" of Ketcham et
// al. 2010): across a sheet, the grey level missing from the rock's, integrated along the
// sheet's normal and divided by the contrast between rock and void, is the aperture — exact
// under any blur that keeps the attenuation, and good to a fraction of a voxel. Each face
// samples the grey levels along its normal at a few points of the face, over a window the
// point spread needs, and takes their mean.
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_GREY_APERTURES_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_GREY_APERTURES_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "absl/status/statusor.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/voxel/grey_volume.h"

namespace sheetmesh {

struct GreyApertureOptions {
  double psf_sigma_voxels = 1.0;  // the scanner's point spread (Gaussian σ), voxels
};

struct GreyApertureStats {
  GreyLevels levels;
  bool measured = false;           // false: the levels allow no aperture (levels.problem)
  uint64_t faces = 0;              // sheet faces given an aperture from the grey levels
  double mean_voxels = 0;          // area-weighted mean aperture
  double counted_mean_voxels = 0;  // the same faces' aperture from the voxel count before
  double uncertainty_voxels = 0;   // one face's aperture's standard error from the noise
  double window_voxels = 0;        // the half width of the integration window, beyond the
                                   // face's own half thickness
  nlohmann::json Fields() const;
};

// Sets mesh->face_aperture_voxels (and the vertices' thickness, the mean of their faces')
// from `grey` for every sheet face (bodies' faces keep theirs); the apertures counted from
// voxels before are summarised beside. Where `levels` allow no aperture, changes nothing
// and says so in the stats. kInvalidArgument when the mesh has no face thickness or
// psf_sigma is not in (0, 8].
absl::StatusOr<GreyApertureStats> SetGreyApertures(TriangleMesh* mesh, const GreyVolume& grey,
                                                   const GreyLevels& levels,
                                                   const GreyApertureOptions& options);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_GREY_APERTURES_H_
