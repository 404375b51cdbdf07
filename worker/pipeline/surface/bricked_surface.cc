#include "worker/pipeline/surface/bricked_surface.h"

#include <algorithm>
#include <climits>
#include <cmath>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "worker/pipeline/scvd/dual_triangles.h"
#include "worker/pipeline/voxel/sheet_analysis.h"

namespace sheetmesh {
namespace {

// The cores along one axis of n voxels: [start, end) pairs of a grid of side `b` whose
// lines pass through `origin`.
std::vector<std::pair<int32_t, int32_t>> AxisCores(int64_t n, int32_t b, int32_t origin) {
  int64_t s = ((origin % b) + b) % b;
  if (s > 0) s -= b;
  std::vector<std::pair<int32_t, int32_t>> out;
  for (int64_t a = s; a < n; a += b) {
    out.emplace_back(static_cast<int32_t>(std::max<int64_t>(a, 0)),
                     static_cast<int32_t>(std::min<int64_t>(a + b, n)));
  }
  return out;
}

Vec3 Global(const Vec3& local, const Index3& lo) { return local + Vec3::Of(lo); }
Index3 Global(const Index3& local, const Index3& lo) {
  return {local.x + lo.x, local.y + lo.y, local.z + lo.z};
}

// Chebyshev distance from `p` to the brick's core, voxels (0 inside).
int64_t CoreDistance(const BrickBox& b, const Index3& p) {
  auto axis = [](int64_t v, int64_t lo, int64_t n) {
    return v < lo ? lo - v : (v >= lo + n ? v - (lo + n) + 1 : 0);
  };
  return std::max({axis(p.x, b.core_lo.x, b.core.nx), axis(p.y, b.core_lo.y, b.core.ny),
                   axis(p.z, b.core_lo.z, b.core.nz)});
}

absl::StatusOr<SheetAnalysis> AnalyzeCrop(const VoxelSet& crop) { return AnalyzeSheet(crop); }

}  // namespace

int SeamBand(double r) { return static_cast<int>(std::ceil(2 * r + 4)); }

int SurfaceHalo(double r, double t_max) {
  return static_cast<int>(std::ceil(std::max(6 * r + 8, t_max + 4 * r) + SeamBand(r)));
}

absl::StatusOr<std::vector<BrickBox>> SurfaceBrickGrid(const Dims& volume,
                                                       const BrickedSurfaceOptions& options) {
  const Dims& b = options.brick;
  if (b.nx < 1 || b.ny < 1 || b.nz < 1) {
    return absl::InvalidArgumentError(absl::StrCat("bricks.brick (", b.nx, ", ", b.ny, ", ", b.nz,
                                                   ") must be at least one voxel a side"));
  }
  if (options.halo < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("bricks.halo ", options.halo, " voxels must not be negative"));
  }
  const int h = options.halo;
  std::vector<BrickBox> out;
  for (const auto& [z0, z1] : AxisCores(volume.nz, b.nz, options.grid_origin.z)) {
    for (const auto& [y0, y1] : AxisCores(volume.ny, b.ny, options.grid_origin.y)) {
      for (const auto& [x0, x1] : AxisCores(volume.nx, b.nx, options.grid_origin.x)) {
        BrickBox box;
        box.core_lo = {x0, y0, z0};
        box.core = {x1 - x0, y1 - y0, z1 - z0};
        box.lo = {std::max(0, x0 - h), std::max(0, y0 - h), std::max(0, z0 - h)};
        const Index3 hi{static_cast<int32_t>(std::min<int64_t>(volume.nx, x1 + h)),
                        static_cast<int32_t>(std::min<int64_t>(volume.ny, y1 + h)),
                        static_cast<int32_t>(std::min<int64_t>(volume.nz, z1 + h))};
        box.dims = {hi.x - box.lo.x, hi.y - box.lo.y, hi.z - box.lo.z};
        box.image = volume;
        out.push_back(box);
      }
    }
  }
  return out;
}

absl::StatusOr<std::vector<Index3>> BrickGenerators(const VoxelSet& crop, const BrickBox& brick,
                                                    double mean_thickness,
                                                    const ScvdOptions& options) {
  std::vector<Index3> out;
  if (crop.empty()) return out;
  SM_ASSIGN_OR_RETURN(SheetAnalysis sheet, AnalyzeCrop(crop));
  ScvdOptions o = options;
  o.local = true;
  o.origin = brick.lo;
  o.mean_thickness_voxels = mean_thickness;
  o.generators = {};
  SM_ASSIGN_OR_RETURN(Scvd scvd,
                      BuildScvd(sheet.set, sheet.neighbors, sheet.components, mean_thickness, o));
  for (const Index3& g : scvd.generators) {
    const Index3 p = Global(g, brick.lo);
    if (brick.InCore(p)) out.push_back(p);
  }
  return out;
}

absl::StatusOr<BrickFaces> BrickTriangles(const VoxelSet& crop, const BrickBox& brick,
                                          std::span<const Index3> generators, double mean_thickness,
                                          const SurfaceOptions& options, int seam_band) {
  BrickFaces out;
  out.crop_voxels = crop.size();
  // `generators` are in (z, y, x) order: only the run of the box's slices is looked at.
  std::vector<Index3> mine;
  const auto first = std::lower_bound(generators.begin(), generators.end(),
                                      Index3{INT32_MIN, INT32_MIN, brick.lo.z}, PositionLess);
  for (auto it = first; it != generators.end() && it->z < brick.lo.z + brick.dims.nz; ++it) {
    const Index3& g = *it;
    if (brick.InBox(g) && crop.Contains(g.x - brick.lo.x, g.y - brick.lo.y, g.z - brick.lo.z)) {
      mine.push_back(g);
    }
  }
  if (mine.empty()) return out;
  SM_ASSIGN_OR_RETURN(SheetAnalysis sheet, AnalyzeCrop(crop));
  ScvdOptions o = options.scvd;
  o.local = true;
  o.origin = brick.lo;
  o.mean_thickness_voxels = mean_thickness;
  o.generators = mine;
  SM_ASSIGN_OR_RETURN(Scvd scvd,
                      BuildScvd(sheet.set, sheet.neighbors, sheet.components, mean_thickness, o));
  const uint32_t num_gen = scvd.num_generators();
  std::vector<Vec3> positions(num_gen);
  for (uint32_t g = 0; g < num_gen; ++g) {
    positions[g] =
        Global(options.placement == VertexPlacement::kCentroid ? scvd.centroid[g]
                                                               : Vec3::Of(scvd.generators[g]),
               brick.lo);
  }
  DualTriangleOptions dual = options.dual;
  dual.origin = brick.lo;
  dual.image = brick.image;
  if (dual.crack_max_edge_voxels <= 0) {
    // A regular mesh whose vertices each stand for one cell's layer of 1 + 2 r (r - 1)
    // voxels (formula 3) has edges of sqrt(2 A / sqrt 3).
    const double r = options.scvd.radius_voxels;
    dual.crack_max_edge_voxels = 1.5 * std::sqrt(2 * (1 + 2 * r * (r - 1)) / std::sqrt(3.0));
  }
  SM_ASSIGN_OR_RETURN(
      DualTriangulation tri,
      TriangulateScvd(sheet.set, sheet.neighbors, sheet.thickness, scvd, positions, dual));
  // Mean τ per cell, for the generators' vertices.
  std::vector<double> tau(num_gen, 0.0);
  for (size_t v = 0; v < scvd.cell.size(); ++v) {
    if (scvd.cell[v] != kNoCell) tau[scvd.cell[v]] += sheet.thickness[v];
  }
  auto generator_of = [&](uint32_t id) { return id < num_gen ? id : tri.rim_cell[id - num_gen]; };
  absl::flat_hash_map<uint32_t, uint32_t> vertex_of;
  for (const Face& f : tri.faces) {
    Index3 least = Global(scvd.generators[generator_of(f[0])], brick.lo);
    for (int k = 1; k < 3; ++k) {
      const Index3 p = Global(scvd.generators[generator_of(f[k])], brick.lo);
      if (PositionLess(p, least)) least = p;
    }
    if (!brick.InCore(least)) {
      if (seam_band > 0 && CoreDistance(brick, least) <= seam_band) {
        SurfaceFaceKey key;
        for (int k = 0; k < 3; ++k) {
          key[k] = {Global(scvd.generators[generator_of(f[k])], brick.lo), f[k] >= num_gen};
        }
        std::sort(key.begin(), key.end());
        out.band.push_back(key);
      }
      continue;
    }
    Face kept;
    for (int k = 0; k < 3; ++k) {
      const auto [it, added] = vertex_of.try_emplace(f[k], static_cast<uint32_t>(out.keys.size()));
      kept[k] = it->second;
      if (!added) continue;
      const uint32_t g = generator_of(f[k]);
      const bool rim = f[k] >= num_gen;
      out.keys.push_back({Global(scvd.generators[g], brick.lo), rim});
      out.positions.push_back(rim ? tri.rim_positions[f[k] - num_gen] : positions[g]);
      out.thickness.push_back(
          rim ? tri.rim_thickness[f[k] - num_gen]
              : static_cast<float>(scvd.cell_size[g] > 0 ? tau[g] / scvd.cell_size[g] : 0.0));
    }
    out.faces.push_back(kept);
  }
  return out;
}

namespace {

// Pass 2 over `grid` and the join into `out` (mesh, keys, counts); returns the seam band's
// mismatches.
absl::StatusOr<uint64_t> TriangulateBricks(const VoxelSet& set, double mean_thickness,
                                           const SurfaceOptions& options,
                                           const std::vector<BrickBox>& grid, int band,
                                           const Progress& progress, BrickedSurface* out) {
  absl::flat_hash_map<SurfaceVertexKey, uint32_t> vertex_of;
  absl::flat_hash_map<SurfaceFaceKey, uint32_t> owner;  // each kept face's brick
  std::vector<absl::flat_hash_set<SurfaceFaceKey>> band_faces(grid.size());
  TriangleMesh& mesh = out->mesh;
  mesh = {};
  out->vertex_key.clear();
  out->bricks = 0;
  out->largest_crop_voxels = 0;
  out->disagreeing_vertices = 0;
  for (size_t i = 0; i < grid.size(); ++i) {
    SM_RETURN_IF_ERROR(progress.Update(double(i) / grid.size()));
    const VoxelSet crop = set.Crop(grid[i].lo, grid[i].dims);
    if (crop.empty()) continue;
    ++out->bricks;
    out->largest_crop_voxels = std::max(out->largest_crop_voxels, crop.size());
    SM_ASSIGN_OR_RETURN(BrickFaces piece, BrickTriangles(crop, grid[i], out->generators,
                                                         mean_thickness, options, band));
    band_faces[i].insert(piece.band.begin(), piece.band.end());
    std::vector<uint32_t> id(piece.keys.size());
    for (size_t v = 0; v < piece.keys.size(); ++v) {
      const auto [it, added] =
          vertex_of.try_emplace(piece.keys[v], static_cast<uint32_t>(mesh.vertices.size()));
      id[v] = it->second;
      if (added) {
        mesh.vertices.push_back(piece.positions[v]);
        mesh.vertex_thickness_voxels.push_back(piece.thickness[v]);
        out->vertex_key.push_back(piece.keys[v]);
      } else if (Norm2(mesh.vertices[it->second] - piece.positions[v]) > 0 ||
                 mesh.vertex_thickness_voxels[it->second] != piece.thickness[v]) {
        ++out->disagreeing_vertices;
      }
    }
    for (const Face& f : piece.faces) {
      SurfaceFaceKey key{piece.keys[f[0]], piece.keys[f[1]], piece.keys[f[2]]};
      std::sort(key.begin(), key.end());
      owner.emplace(key, static_cast<uint32_t>(i));
      mesh.faces.push_back({id[f[0]], id[f[1]], id[f[2]]});
    }
  }
  // Every band face a brick built is one its owner kept; every kept face near another core
  // is one that brick built.
  uint64_t mismatches = 0;
  for (const auto& faces : band_faces) {
    for (const SurfaceFaceKey& key : faces) mismatches += !owner.contains(key);
  }
  for (const auto& [key, i] : owner) {
    const Index3& least = key[0].generator;
    const BrickBox& own = grid[i];
    const int64_t inside =
        std::min<int64_t>({least.x - own.core_lo.x, own.core_lo.x + own.core.nx - 1 - least.x,
                           least.y - own.core_lo.y, own.core_lo.y + own.core.ny - 1 - least.y,
                           least.z - own.core_lo.z, own.core_lo.z + own.core.nz - 1 - least.z});
    if (inside >= band) continue;  // no other core within the band
    for (size_t j = 0; j < grid.size(); ++j) {
      if (j == i || CoreDistance(grid[j], least) > band) continue;
      mismatches += !band_faces[j].contains(key);
    }
  }
  return mismatches;
}

}  // namespace

std::vector<SurfaceFaceKey> FaceKeys(const BrickedSurface& s) {
  std::vector<SurfaceFaceKey> out;
  out.reserve(s.mesh.faces.size());
  for (const Face& f : s.mesh.faces) {
    SurfaceFaceKey key{s.vertex_key[f[0]], s.vertex_key[f[1]], s.vertex_key[f[2]]};
    std::sort(key.begin(), key.end());
    out.push_back(key);
  }
  std::sort(out.begin(), out.end());
  return out;
}

absl::StatusOr<BrickedSurface> BuildBrickedSurface(const VoxelSet& set, double mean_thickness,
                                                   const SurfaceOptions& options,
                                                   const BrickedSurfaceOptions& bricks,
                                                   std::span<const Index3> generators,
                                                   const Progress& progress) {
  SM_ASSIGN_OR_RETURN(std::vector<BrickBox> grid, SurfaceBrickGrid(set.dims(), bricks));
  BrickedSurface out;
  const double pass1 = generators.empty() ? 0.4 : 0.0;
  if (generators.empty()) {
    for (size_t i = 0; i < grid.size(); ++i) {
      SM_RETURN_IF_ERROR(progress.Update(pass1 * i / grid.size()));
      const VoxelSet crop = set.Crop(grid[i].lo, grid[i].dims);
      SM_ASSIGN_OR_RETURN(std::vector<Index3> mine,
                          BrickGenerators(crop, grid[i], mean_thickness, options.scvd));
      out.generators.insert(out.generators.end(), mine.begin(), mine.end());
    }
  } else {
    out.generators.assign(generators.begin(), generators.end());
  }
  std::sort(out.generators.begin(), out.generators.end(), PositionLess);

  BrickedSurfaceOptions o = bricks;
  const double r = options.scvd.radius_voxels;
  for (int attempt = 0;; ++attempt) {
    const int band =
        std::min(o.halo, o.seam_band > 0 ? o.seam_band : static_cast<int>(std::ceil(2 * r + 4)));
    const double lo = pass1 + (1 - pass1) * (1 - std::pow(0.5, attempt));
    const Progress step = progress.Sub(lo, pass1 + (1 - pass1) * (1 - std::pow(0.5, attempt + 1)));
    SM_ASSIGN_OR_RETURN(out.seam_mismatches,
                        TriangulateBricks(set, mean_thickness, options, grid, band, step, &out));
    out.halo = o.halo;
    out.retries = attempt;
    // A vertex two bricks computed apart is a seam's disagreement too.
    out.seam_mismatches += out.disagreeing_vertices;
    if (out.seam_mismatches == 0 || attempt >= o.retries) break;
    o.halo = std::max(1, 2 * o.halo);
    SM_ASSIGN_OR_RETURN(grid, SurfaceBrickGrid(set.dims(), o));
  }
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return out;
}

}  // namespace sheetmesh
