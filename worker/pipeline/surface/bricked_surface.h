// The SCVD and its dual triangles built brick by brick (issue 47): every per-voxel structure
// (neighbours, thickness, cells, candidate triangles) lives for one brick and its halo only,
// so these stages' memory follows the brick, not the sheet. Two passes over the bricks with
// one gathering between them:
//  1. each brick draws local generators (ScvdOptions::local) over its core and halo, runs
//     its Lloyd steps there and keeps the generators in its core;
//  2. with every brick's generators gathered, each brick grows cells once from those in its
//     core and halo, triangulates them, and keeps the faces whose least generator (by
//     (z, y, x)) is in its core, with their vertices' positions and thicknesses.
// A growth and the triangle selection reach a bounded distance, so where the halo is wider,
// pass 2 gives in each core exactly what the whole volume gives from the same generators:
// the bricks' faces join into one surface with no seam, no gap and no duplicate. Pass 1 is
// local too but reaches further with every Lloyd step; where its halo falls short,
// generators near a seam sit a little off where the whole volume would put them — less
// regular cells there, never a gap (pass 2 covers every voxel a generator reaches).
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_BRICKED_SURFACE_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_BRICKED_SURFACE_H_

#include <cstdint>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "common/progress.h"
#include "common/types.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/surface/surface_options.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// One brick: the voxels it owns and the box it reads (core and halo, within the volume).
struct BrickBox {
  Index3 core_lo;
  Dims core;
  Index3 lo;
  Dims dims;
  Dims image;  // the whole image's size

  bool InCore(const Index3& p) const {
    return p.x >= core_lo.x && p.y >= core_lo.y && p.z >= core_lo.z && p.x < core_lo.x + core.nx &&
           p.y < core_lo.y + core.ny && p.z < core_lo.z + core.nz;
  }
  bool InBox(const Index3& p) const {
    return p.x >= lo.x && p.y >= lo.y && p.z >= lo.z && p.x < lo.x + dims.nx &&
           p.y < lo.y + dims.ny && p.z < lo.z + dims.nz;
  }
};

struct BrickedSurfaceOptions {
  Dims brick{256, 256, 256};  // the grid's cell, voxels
  int halo = 64;              // voxels read around each core
  Index3 grid_origin;         // a corner of the grid (the lines pass through it)
  // The seam check: each brick also gives the faces it built whose least generator lies
  // outside its core but within this many voxels of it (0: SeamBand(r)), and the join checks
  // them against the faces their owners kept, both ways. Where they differ, pass 2 runs
  // again with twice the halo, up to `retries` times.
  int seam_band = 0;
  int retries = 2;
};

// The halo pass 2 and its seam check need for cells of radius r on a sheet whose longest
// thickness run is t_max voxels: max(6 r + 8, t_max + 4 r) for the faces of a core — a
// face's far corner is about 2 r from its owner's core, its cell r further, and the
// thickness there reads runs of up to t_max — and the seam band (SeamBand) more, so that the
// faces a brick builds just outside its core, which the check compares, are exact too.
// Measured, not proven (bench/RESULTS.md, "The SCVD and its triangles in bricks"): on six
// presets at r = 2 to 15 the cores' faces were exact from halos of 16 to 80 voxels, each at
// or below the first part; a cell stretched along a narrow strip can reach further, which
// the seam check (BrickedSurfaceOptions::seam_band) finds and mends.
int SeamBand(double r);  // 2 r + 4, voxels
int SurfaceHalo(double r, double t_max);

// The bricks covering `volume`, in (z, y, x) order. kInvalidArgument for a brick side below
// 1 or a negative halo, naming the field and value.
absl::StatusOr<std::vector<BrickBox>> SurfaceBrickGrid(const Dims& volume,
                                                       const BrickedSurfaceOptions& options);

// (z, y, x) order of global positions: generators' ids and faces' owners follow it.
inline bool PositionLess(const Index3& a, const Index3& b) {
  if (a.z != b.z) return a.z < b.z;
  if (a.y != b.y) return a.y < b.y;
  return a.x < b.x;
}

// Pass 1 for one brick: `crop` is the set's voxels in brick.lo/dims (set.Crop); the
// generators (global positions) its local SCVD puts in its core. `mean_thickness` is the
// whole sheet's t̄.
absl::StatusOr<std::vector<Index3>> BrickGenerators(const VoxelSet& crop, const BrickBox& brick,
                                                    double mean_thickness,
                                                    const ScvdOptions& options);

// A vertex of the joined surface: a generator, or the rim vertex of a generator's cell.
struct SurfaceVertexKey {
  Index3 generator;
  bool rim = false;
  friend bool operator==(const SurfaceVertexKey&, const SurfaceVertexKey&) = default;
  friend bool operator<(const SurfaceVertexKey& a, const SurfaceVertexKey& b) {
    return PositionLess(a.generator, b.generator) || (a.generator == b.generator && a.rim < b.rim);
  }
  template <typename H>
  friend H AbslHashValue(H h, const SurfaceVertexKey& k) {
    return H::combine(std::move(h), k.generator.x, k.generator.y, k.generator.z, k.rim);
  }
};

// A face by its corners' keys, sorted: the same in every brick that builds it.
using SurfaceFaceKey = std::array<SurfaceVertexKey, 3>;

// What pass 2 of one brick keeps: its faces and their vertices (global positions, the mean
// τ along the axis runs over the vertex's cell or rim).
struct BrickFaces {
  std::vector<Face> faces;  // into the lists below
  std::vector<SurfaceVertexKey> keys;
  std::vector<Vec3> positions;
  std::vector<float> thickness;
  // The seam band's faces (least generator outside the core, within `seam_band` of it).
  std::vector<SurfaceFaceKey> band;
  uint64_t crop_voxels = 0;
};

// Pass 2 for one brick: one growth from `generators` (all bricks', global positions in
// PositionLess order; those outside the brick's box are passed by), the dual triangles
// (options.dual, options.placement), the faces owned by the core. Every position is computed in the
// whole image's frame, so a vertex two bricks both give is the same to the last bit; cracks close
// up to 1.5 times the edge of a regular mesh of cells of radius r (not the brick's mean).
absl::StatusOr<BrickFaces> BrickTriangles(const VoxelSet& crop, const BrickBox& brick,
                                          std::span<const Index3> generators, double mean_thickness,
                                          const SurfaceOptions& options, int seam_band = 0);

struct BrickedSurface {
  TriangleMesh mesh;  // vertices, faces, vertex_thickness_voxels (axis runs)
  std::vector<SurfaceVertexKey> vertex_key;
  std::vector<Index3> generators;  // all, in (z, y, x) order
  uint64_t bricks = 0;             // bricks with sheet voxels
  uint64_t largest_crop_voxels = 0;
  // Vertices two bricks placed apart or gave another thickness (0 when the halo covers
  // pass 2's reach: each face is kept by the one brick owning its least generator, so the
  // join cannot hold a face twice, but only a halo wide enough makes the bricks agree).
  uint64_t disagreeing_vertices = 0;
  // Faces of a seam band that the owner or a neighbour did not build alike, and vertices
  // placed apart, at the halo finally used (0 unless the retries ran out), and that halo.
  uint64_t seam_mismatches = 0;
  int halo = 0;
  int retries = 0;  // pass 2 runs beyond the first
};

// Each face of `s` by its corners' keys, sorted: what two surfaces built from the same
// generators compare by, whatever their vertex numbering.
std::vector<SurfaceFaceKey> FaceKeys(const BrickedSurface& s);

// Both passes over the bricks of `set` and the join, checked at the seams (see
// BrickedSurfaceOptions::seam_band). With `generators` given, pass 1 is skipped and those
// are used (global positions). kInvalidArgument as SurfaceBrickGrid and
// BuildScvd; kCancelled if asked.
absl::StatusOr<BrickedSurface> BuildBrickedSurface(const VoxelSet& set, double mean_thickness,
                                                   const SurfaceOptions& options,
                                                   const BrickedSurfaceOptions& bricks,
                                                   std::span<const Index3> generators = {},
                                                   const Progress& progress = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_BRICKED_SURFACE_H_
