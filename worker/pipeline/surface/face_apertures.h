// The aperture each sheet face delivers to a flow model, beside its thickness: the fit of
// face heights (wall_fit.h) chooses the heights that score best together, which leaves a
// face its neighbours' prisms already cover at 0 and gives a face at a junction the voxels
// of the sheets crossing it. Its aperture is the opening of the sheet it belongs to.
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_FACE_APERTURES_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_FACE_APERTURES_H_

#include <cstdint>
#include <span>

#include "worker/pipeline/mesh/triangle_mesh.h"

namespace sheetmesh {

struct FaceApertureStats {
  uint64_t covered = 0;           // faces at 0 that pass through the sheet: given their sheet's
  uint64_t holes = 0;             // faces at 0 over no sheet voxel: they stay 0
  uint64_t junction = 0;          // faces with a vertex on a junction (an edge of 3+ faces)
  uint64_t junction_lowered = 0;  // of those, faces thicker than their sheet, lowered to it
  uint64_t junction_raised = 0;   // of those, faces thinner than their sheet, raised to it
};

// Sets mesh->face_aperture_voxels: each face's thickness, except two kinds of faces, which take
// their sheet's local opening (the area-weighted mean thickness of the faces of the same
// piece, neither of these kinds, within `rings` rings of faces; else the piece's
// area-weighted median; else `measured`): faces at 0 whose `measured` thickness (the mean τ
// of the voxels they pass through) is above 0, and faces at a junction. Faces over no voxel
// stay 0; so do bodies' faces, which have no thickness.
FaceApertureStats SetFaceApertures(TriangleMesh* mesh, std::span<const float> measured,
                                   int rings = 3);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_FACE_APERTURES_H_
