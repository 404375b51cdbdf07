// SurfaceOptions: how BuildSurface (surface_builder.h) and the bricked build
// (bricked_surface.h) mesh a sheet set.
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_SURFACE_OPTIONS_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_SURFACE_OPTIONS_H_

#include <cstdint>

#include "worker/pipeline/scvd/dual_triangle_types.h"
#include "worker/pipeline/scvd/scvd.h"
#include "worker/pipeline/similarity/face_attributes.h"

namespace sheetmesh {

enum class VertexPlacement {
  kGenerator,  // the generator's voxel centre (the paper)
  kCentroid,   // the centroid of the generator's cell (off-voxel, on the mid-surface of flat
               // sheets)
};

// How far a surface's triangle count may land from a count asked for (`--triangles`,
// SurfaceOptions::triangles), as a fraction of it: the radius search's aim and the
// pipeline's check of the count it got.
inline constexpr double kTriangleTolerance = 0.05;

// Which vertices the fit to formula 5 moves (vertex_fit.h).
enum class VertexFit {
  kAuto,  // kRim where the surface is the result, kNone where a volume mesh follows (the
          // pipeline decides; BuildSurface takes it as kRim)
  kNone,
  kRim,  // rims across themselves and onto the box's faces
  kAll,  // and every vertex along its normal
};

// The smallest brick side surface.bricks takes: smaller bricks read their halos many times
// over (the sheet's own floor, 4 r + its thickest run and the halo, is checked on the sheet).
inline constexpr int kMinSurfaceBrick = 32;

// The SCVD and its triangles built brick by brick (bricked_surface.h; beyond the paper).
struct SurfaceBrickOptions {
  int brick = 0;  // > 0: bricks of this side, at least kMinSurfaceBrick, voxels (0: whole)
  int halo = 0;   // voxels read around each brick (0: SurfaceHalo of r and the longest τ)
};

// How a sheet's one layer of triangles is made.
enum class SurfaceMethod {
  kScvd,  // the paper's: the dual triangles of the SCVD of radius r
  kMid,   // the mid-surface at voxel resolution with its aperture, decimated to the budget
          // (mid_surface.h, aperture_decimate.h; beyond the paper)
  kAuto,  // both, and the mid-surface kept unless it scores below the SCVD's (its junctions
          // are at the rock's angles, the SCVD's are not)
};

struct SurfaceOptions {
  SurfaceMethod method = SurfaceMethod::kScvd;
  ScvdOptions scvd;          // r, seed, Lloyd settings
  DualTriangleOptions dual;  // which dual triangles are kept (rim strip, cracks, folds)
  // With bricks the SCVD is local (ScvdOptions::local) and the rest runs on the joined mesh.
  SurfaceBrickOptions bricks;
  VertexPlacement placement = VertexPlacement::kCentroid;
  ThicknessMeasure thickness = ThicknessMeasure::kNormal;
  bool orient = true;      // orient faces consistently per manifold piece
  uint64_t triangles = 0;  // > 0: the dual mesh is decimated to this many faces (decimate.h)
  bool fit_walls = true;   // each face's thickness fitted to the prisms' best formula-5 score
                           // (wall_fit.h; beyond the paper; false: the mean τ)
  VertexFit fit_vertices = VertexFit::kAuto;  // with fit_walls: vertices moved where
                                              // formula 5 rises (vertex_fit.h; beyond the paper)
  double error_density = 0;    // > 0: a second SCVD with ρ from the first surface's local fit
                               // error, this strong (error_density.h; beyond the paper)
  int smooth_iterations = 30;  // λ|μ smoothing pairs where the sheet is thicker than the
                               // triangles are wide (smooth.h; beyond the paper; 0: none)

  // The paper's plain reading: generators as vertices, no rim strip, axis-run thickness.
  static SurfaceOptions Paper();
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_SURFACE_OPTIONS_H_
