// Decimation of a sheet mesh that carries its aperture (beyond the paper): edge collapses by
// a quadric in (x, y, z, t/2) — Garland & Heckbert's quadric with an attribute (1998), each
// face the plane through its three corners lifted by half their thickness — so a collapse
// costs what it moves the sheet's two walls, not its mid-surface alone: where the aperture
// changes, triangles stay. Rims are held by planes across their edges and move along
// themselves; vertices on feature lines (junctions, marked) move only along their line, and
// the ends of a line stay.
#ifndef SHEETMESH_WORKER_PIPELINE_MESH_APERTURE_DECIMATE_H_
#define SHEETMESH_WORKER_PIPELINE_MESH_APERTURE_DECIMATE_H_

#include <cstdint>
#include <vector>

#include "worker/pipeline/mesh/triangle_mesh.h"

namespace sheetmesh {

struct ApertureDecimateOptions {
  uint64_t triangles = 0;         // collapse until at most this many faces remain
  double boundary_weight = 8.0;   // weight of the planes across rim edges (per length²)
  double feature_weight = 64.0;   // weight of the planes along feature lines (per length²)
  double max_normal_turn = 60.0;  // degrees a face's normal may turn in one collapse
  double max_error = 1e300;       // stop once the cheapest collapse costs more (voxels²)
  // A collapse may not leave a face with an angle under this many degrees, unless the face
  // had one as small before; once no other collapse is left short of the target, the rest
  // are made without it. Flat sheets decimate freely (any collapse in a plane costs
  // nothing), and needles of a fraction of a voxel across pin a volume mesh's slivers.
  // 0: no bound.
  double min_angle_degrees = 0;
  // Per vertex, 1 where it lies on a feature line that must stay (a junction curve); empty:
  // none beyond edges of three or more faces, which are feature lines always.
  std::vector<uint8_t> feature;
  // Per vertex, 1 where it must not move at all (a feature line's end, a box corner).
  std::vector<uint8_t> pinned;
};

struct ApertureDecimateStats {
  uint64_t faces_before = 0;
  uint64_t faces_after = 0;
  uint64_t collapses = 0;
  uint64_t unshaped_collapses = 0;  // made after the angle bound had to be let go
  double largest_error = 0;         // the cost of the dearest collapse made (voxels²)
};

// Decimates `mesh` in place. REQUIRES: mesh->vertex_thickness_voxels has one value per
// vertex. It, face_piece and the vertices follow the collapses; face_thickness_voxels is set
// to the mean of each face's corners'. A collapse that would change the mesh's topology,
// join two pieces, flip or fold a face, take a rim vertex inside or a feature vertex off its
// line is not made, so the target may not be reached.
ApertureDecimateStats DecimateWithAperture(TriangleMesh* mesh,
                                           const ApertureDecimateOptions& options);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_MESH_APERTURE_DECIMATE_H_
