#include "worker/pipeline/surface/surface_builder.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "common/status_macros.h"
#include "worker/pipeline/mesh/aperture_decimate.h"
#include "worker/pipeline/mesh/decimate.h"
#include "worker/pipeline/mesh/mesh_io.h"
#include "worker/pipeline/mesh/mesh_topology.h"
#include "worker/pipeline/mesh/smooth.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/similarity/face_attributes.h"
#include "worker/pipeline/surface/bricked_surface.h"
#include "worker/pipeline/surface/face_apertures.h"
#include "worker/pipeline/surface/mid_surface.h"
#include "worker/pipeline/surface/wall_fit.h"

namespace sheetmesh {

namespace {

// The dual mesh before any fitting goes into out->mesh (vertices, faces) and
// out->vertex_generator (an index into out->scvd); beside them, each vertex's mean τ along
// the axis runs.
struct DualMesh {
  std::vector<double> vertex_tau;  // double: rounded to float once, after the normal's factor
};

absl::StatusOr<DualMesh> WholeDualMesh(const SheetAnalysis& sheet, const SurfaceOptions& options,
                                       const Progress& progress, SurfaceResult* out) {
  absl::Time t0 = absl::Now();
  SM_ASSIGN_OR_RETURN(
      out->scvd, BuildScvd(sheet.set, sheet.neighbors, sheet.components, sheet.thickness_stats.mean,
                           options.scvd, progress.Sub(0, 0.7)));
  out->scvd_seconds = absl::ToDoubleSeconds(absl::Now() - t0);
  const Scvd& scvd = out->scvd;

  t0 = absl::Now();
  std::vector<Vec3> positions(scvd.num_generators());
  for (uint32_t g = 0; g < scvd.num_generators(); ++g) {
    positions[g] = options.placement == VertexPlacement::kCentroid ? scvd.centroid[g]
                                                                   : Vec3::Of(scvd.generators[g]);
  }
  SM_ASSIGN_OR_RETURN(DualTriangulation tri,
                      TriangulateScvd(sheet.set, sheet.neighbors, sheet.thickness, scvd, positions,
                                      options.dual, progress.Sub(0.7, 0.9)));
  // Rim vertices follow the generators in the vertex numbering of `tri`.
  const uint32_t num_gen = scvd.num_generators();
  for (size_t k = 0; k < tri.rim_positions.size(); ++k) positions.push_back(tri.rim_positions[k]);
  out->triangle_stats = tri.stats;
  out->triangles_seconds = absl::ToDoubleSeconds(absl::Now() - t0);

  // Per-vertex thickness: the mean τ over the generator's cell, or over a rim's voxels.
  std::vector<double> cell_tau(scvd.num_generators(), 0.0);
  for (size_t v = 0; v < scvd.cell.size(); ++v) {
    if (scvd.cell[v] != kNoCell) cell_tau[scvd.cell[v]] += sheet.thickness[v];
  }
  // Compact: only generators used by a face become vertices.
  DualMesh dual;
  std::vector<uint32_t> vertex_of(positions.size(), UINT32_MAX);
  TriangleMesh& mesh = out->mesh;
  for (const Face& f : tri.faces) {
    Face g;
    for (int k = 0; k < 3; ++k) {
      uint32_t& v = vertex_of[f[k]];
      if (v == UINT32_MAX) {
        v = static_cast<uint32_t>(mesh.vertices.size());
        mesh.vertices.push_back(positions[f[k]]);
        const uint32_t gen = f[k] < num_gen ? f[k] : tri.rim_cell[f[k] - num_gen];
        out->vertex_generator.push_back(gen);
        dual.vertex_tau.push_back(
            f[k] >= num_gen
                ? tri.rim_thickness[f[k] - num_gen]
                : (scvd.cell_size[gen] > 0 ? cell_tau[gen] / scvd.cell_size[gen] : 0.0));
      }
      g[k] = v;
    }
    mesh.faces.push_back(g);
  }
  return dual;
}

absl::StatusOr<DualMesh> BrickedDualMesh(const SheetAnalysis& sheet, const SurfaceOptions& options,
                                         const Progress& progress, SurfaceResult* out) {
  if (!options.scvd.density.empty()) {
    return absl::InvalidArgumentError(
        "surface.bricks cannot take an error-driven density (surface.error_density): its scale "
        "is the whole sheet's");
  }
  absl::Time t0 = absl::Now();
  SurfaceOptions local = options;
  if (local.scvd.generator_count > 0) {
    // A count over the whole sheet: the r whose cells (formula 3) give it, so that every
    // brick draws at the same rate: t (1 + 2 r (r - 1)) = voxels / count.
    const double layer = double(sheet.set.size()) /
                         (double(local.scvd.generator_count) * sheet.thickness_stats.mean);
    local.scvd.radius_voxels = 0.5 * (1 + std::sqrt(std::max(0.0, 2 * layer - 1)));
    local.scvd.generator_count = 0;
  }
  BrickedSurfaceOptions bo;
  bo.brick = {options.bricks.brick, options.bricks.brick, options.bricks.brick};
  const uint16_t t_max = sheet.thickness.empty()
                             ? 0
                             : *std::max_element(sheet.thickness.begin(), sheet.thickness.end());
  bo.halo =
      options.bricks.halo > 0 ? options.bricks.halo : SurfaceHalo(local.scvd.radius_voxels, t_max);
  // A brick narrower than its cells and the sheet's thickness, or than the halo it reads,
  // does the whole sheet's work many times over (1 voxel: once a voxel, for ever).
  const int floor =
      std::max(static_cast<int>(std::ceil(4 * local.scvd.radius_voxels)) + int{t_max}, bo.halo);
  if (options.bricks.brick < floor) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "surface.bricks = %d is below the smallest brick for r = %.3g on this sheet: max(4 r + "
        "its thickest run %d, the halo %d) = %d voxels; give at least %d, or 0 to build the "
        "surface whole",
        options.bricks.brick, local.scvd.radius_voxels, int{t_max}, bo.halo, floor, floor));
  }
  SM_ASSIGN_OR_RETURN(BrickedSurface b, BuildBrickedSurface(sheet.set, sheet.thickness_stats.mean,
                                                            local, bo, {}, progress.Sub(0, 0.9)));
  out->bricks = b.bricks;
  out->brick_halo = b.halo;
  out->seam_mismatches = b.seam_mismatches;
  // The diagram's figures: its generators, where they lie and in which component.
  Scvd& scvd = out->scvd;
  scvd.generators = std::move(b.generators);
  scvd.mean_thickness = sheet.thickness_stats.mean;
  scvd.cell_volume = CellVolume(scvd.mean_thickness, local.scvd.radius_voxels);
  scvd.iterations = local.scvd.lloyd_max_iter + 1;
  const std::vector<uint32_t> label = sheet.components.VoxelLabels(sheet.set);
  for (const Index3& g : scvd.generators) {
    const int64_t v = sheet.set.Find(g.x, g.y, g.z);
    scvd.generator_voxel.push_back(static_cast<uint32_t>(v));
    scvd.generator_component.push_back(label[v]);
  }
  for (const SurfaceVertexKey& k : b.vertex_key) {
    const auto it =
        std::lower_bound(scvd.generators.begin(), scvd.generators.end(), k.generator, PositionLess);
    out->vertex_generator.push_back(static_cast<uint32_t>(it - scvd.generators.begin()));
  }
  out->mesh = std::move(b.mesh);
  DualMesh dual;
  dual.vertex_tau.assign(out->mesh.vertex_thickness_voxels.begin(),
                         out->mesh.vertex_thickness_voxels.end());
  out->mesh.vertex_thickness_voxels.clear();
  out->scvd_seconds = absl::ToDoubleSeconds(absl::Now() - t0);
  return dual;
}

// With options.fit_walls: each face's height fitted to formula 5, then (fit_vertices) the
// vertices moved where it rises and the heights fitted again; `measured` gives the faces'
// measured thickness as they lie then, each face's aperture for a flow model.
void FitWallsAndVertices(const SheetAnalysis& sheet, const SurfaceOptions& options,
                         SurfaceResult* out, const std::function<std::vector<float>()>& measured) {
  if (!options.fit_walls) return;
  TriangleMesh& mesh = out->mesh;
  // Up to twice the mean-τ height and 4 voxels more: room for a wall the mean misses.
  std::vector<float> apertures = mesh.face_thickness_voxels;
  std::vector<float> search(mesh.face_thickness_voxels.size());
  for (size_t f = 0; f < search.size(); ++f) search[f] = 2 * mesh.face_thickness_voxels[f] + 4;
  mesh.face_thickness_voxels = FitFaceThickness(mesh, sheet.set, search);
  if (options.fit_vertices != VertexFit::kNone) {
    VertexFitOptions fit;
    fit.along_normal = options.fit_vertices == VertexFit::kAll;
    out->vertex_fit = FitVertexPositions(&mesh, sheet.set, fit);
    // The heights again, for the faces as they lie now.
    if (out->vertex_fit->moves > 0) {
      mesh.face_thickness_voxels = FitFaceThickness(mesh, sheet.set, search);
      apertures = measured();
    }
  }
  // The fitted heights score best together; a flow model takes each face's aperture as its
  // sheet's (0 only over a hole, a junction's face not the crossing sheets' sum).
  out->apertures = SetFaceApertures(&mesh, apertures);
}

// The triangles the SCVD of radius r gives a sheet of `voxels` voxels of mean thickness t
// (formula 3: a generator per cell of t (1 + 2 r (r - 1)) voxels, about two triangles per
// generator): what r asks of a surface made another way.
uint64_t TrianglesOfRadius(uint64_t voxels, double mean_thickness, double r) {
  const double cell = CellVolume(std::max(1.0, mean_thickness), r);
  return std::max<uint64_t>(2, static_cast<uint64_t>(std::llround(2.0 * voxels / cell)));
}

// The mid-surface of each piece with its aperture, decimated to the budget (options.triangles,
// else what r gives the SCVD), then the fits the SCVD's surface gets.
absl::StatusOr<SurfaceResult> BuildMidSurfaceResult(const SheetAnalysis& sheet,
                                                    const SurfaceOptions& options,
                                                    std::span<const int32_t> piece_of_voxel,
                                                    const Progress& progress) {
  SurfaceResult out;
  absl::Time t0 = absl::Now();
  SM_ASSIGN_OR_RETURN(MidSurface mid,
                      BuildMidSurface(sheet.set, piece_of_voxel, progress.Sub(0, 0.3)));
  out.mesh = std::move(mid.mesh);
  out.scvd_seconds = absl::ToDoubleSeconds(absl::Now() - t0);
  t0 = absl::Now();
  const uint64_t target = options.triangles > 0
                              ? options.triangles
                              : TrianglesOfRadius(sheet.set.size(), sheet.thickness_stats.mean,
                                                  options.scvd.radius_voxels);
  if (out.mesh.faces.size() > target) {
    ApertureDecimateOptions d;
    d.triangles = target;
    d.pinned = OutlineCornersOnBox(out.mesh.vertices, sheet.set.dims());
    // Triangles fit for a volume mesh: no collapse leaves an angle under 10 degrees while
    // another can still be made.
    d.min_angle_degrees = 10;
    const ApertureDecimateStats s = DecimateWithAperture(&out.mesh, d);
    out.decimation = DecimateStats{s.faces_before, s.faces_after, s.collapses, s.largest_error};
  }
  out.triangles_seconds = absl::ToDoubleSeconds(absl::Now() - t0);
  SM_RETURN_IF_ERROR(progress.Update(0.8));
  t0 = absl::Now();
  TriangleMesh& mesh = out.mesh;
  FitWallsAndVertices(sheet, options, &out, [&] {
    // The thickness each face's corners carry, as measured across the sheet.
    std::vector<float> t(mesh.faces.size());
    for (size_t f = 0; f < t.size(); ++f) {
      const Face& c = mesh.faces[f];
      t[f] = (mesh.vertex_thickness_voxels[c[0]] + mesh.vertex_thickness_voxels[c[1]] +
              mesh.vertex_thickness_voxels[c[2]]) /
             3;
    }
    return t;
  });
  // The sheets meet at their planes' angle: what decimation and the fits moved near a
  // junction goes back onto its piece's plane there.
  FlattenAtJunctions(&mesh, mid.junctions);
  SettleAtBox(sheet.set.dims(), &mesh);
  out.components = sheet.components.count();
  out.attributes_seconds = absl::ToDoubleSeconds(absl::Now() - t0);
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return out;
}

}  // namespace

absl::StatusOr<SurfaceResult> BuildSurface(const SheetAnalysis& sheet,
                                           const SurfaceOptions& options,
                                           std::span<const int32_t> piece_of_voxel,
                                           const Progress& progress) {
  if (options.method == SurfaceMethod::kMid) {
    return BuildMidSurfaceResult(sheet, options, piece_of_voxel, progress);
  }
  SurfaceResult out;
  SM_ASSIGN_OR_RETURN(DualMesh dual,
                      options.bricks.brick > 0
                          ? BrickedDualMesh(sheet, options, progress.Sub(0, 0.9), &out)
                          : WholeDualMesh(sheet, options, progress.Sub(0, 0.9), &out));
  const Scvd& scvd = out.scvd;
  TriangleMesh& mesh = out.mesh;
  absl::Time t0 = absl::Now();
  if (options.orient) OrientConsistently(&mesh);
  // Vertex normals (faces are oriented now, or flipped to agree) for the per-vertex measure.
  std::vector<Vec3> vnormal(mesh.vertices.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const Vec3 n = AreaVector(Corners(mesh, f));
    for (uint32_t v : mesh.faces[f]) vnormal[v] += Dot(vnormal[v], n) < 0 ? -n : n;
  }
  mesh.vertex_thickness_voxels.resize(mesh.vertices.size());
  std::vector<int32_t> vertex_piece(mesh.vertices.size());
  for (uint32_t v = 0; v < mesh.vertices.size(); ++v) {
    const uint32_t g = out.vertex_generator[v];
    double tau = dual.vertex_tau[v];
    if (options.thickness == ThicknessMeasure::kNormal) {
      tau *= AxisRunToNormalFactor(Normalized(vnormal[v]));
    }
    mesh.vertex_thickness_voxels[v] = static_cast<float>(tau);
    vertex_piece[v] = piece_of_voxel.empty() ? static_cast<int32_t>(scvd.generator_component[g])
                                             : piece_of_voxel[scvd.generator_voxel[g]];
  }
  mesh.face_piece = FaceLabels(mesh, vertex_piece);
  if (options.smooth_iterations > 0) {
    SmoothOptions so;
    so.iterations = options.smooth_iterations;
    out.smoothed_vertices =
        SmoothVertices(&mesh, ThicknessSmoothingWeights(mesh, mesh.vertex_thickness_voxels), so);
  }
  if (options.triangles > 0 && mesh.faces.size() > options.triangles) {
    DecimateOptions d;
    d.triangles = options.triangles;
    out.decimation = Decimate(&mesh, d);
  }
  mesh.face_thickness_voxels = FaceThickness(mesh, sheet.set, sheet.thickness, options.thickness);
  FitWallsAndVertices(sheet, options, &out, [&] {
    return FaceThickness(mesh, sheet.set, sheet.thickness, options.thickness);
  });
  if (out.decimation) {
    // The vertices are no longer generators: each takes its faces' mean thickness.
    std::vector<double> sum(mesh.vertices.size(), 0.0), area(mesh.vertices.size(), 0.0);
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      const double a = Area(Corners(mesh, f));
      for (uint32_t v : mesh.faces[f]) {
        sum[v] += a * mesh.face_thickness_voxels[f];
        area[v] += a;
      }
    }
    mesh.vertex_thickness_voxels.resize(mesh.vertices.size());
    for (size_t v = 0; v < sum.size(); ++v) {
      mesh.vertex_thickness_voxels[v] = static_cast<float>(area[v] > 0 ? sum[v] / area[v] : 0.0);
    }
  }

  // Components that gave no triangle.
  out.components = sheet.components.count();
  std::vector<uint8_t> meshed(out.components, 0);
  for (uint32_t g : out.vertex_generator) meshed[scvd.generator_component[g]] = 1;
  for (uint32_t c = 0; c < out.components; ++c) {
    if (meshed[c]) continue;
    ++out.skipped_components;
    out.skipped_voxels += sheet.components.sizes[c];
    if (out.largest_skipped.size() < 20) {
      out.largest_skipped.push_back({c, sheet.components.sizes[c]});  // sizes are descending
    }
  }
  out.attributes_seconds = absl::ToDoubleSeconds(absl::Now() - t0);
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return out;
}

SurfaceStats DescribeSurface(const SurfaceResult& result, const Placement& placement) {
  const TriangleMesh& mesh = result.mesh;
  SurfaceStats s;
  s.decimation = result.decimation;
  s.vertex_fit = result.vertex_fit;
  s.apertures = result.apertures;
  s.smoothed_vertices = result.smoothed_vertices;
  s.error_density = result.error_density;
  s.mesher_choice = result.mesher_choice;
  s.generators = result.scvd.num_generators();
  s.lloyd_iterations = result.scvd.iterations;
  s.lloyd_converged = result.scvd.converged;
  s.energy = result.scvd.energy.empty() ? 0 : result.scvd.energy.back();
  s.vertices = mesh.num_vertices();
  s.triangles = mesh.num_faces();
  s.element_size_voxels = MeanEdgeLength(mesh);
  s.element_size = PhysicalLength(s.element_size_voxels, placement);
  s.area_voxels = SurfaceArea(mesh);
  s.triangle_stats = result.triangle_stats;
  s.topology = AnalyzeTopology(mesh);
  s.topology.nonmanifold_edge_list.clear();
  s.skipped_components = result.skipped_components;
  s.skipped_voxels = result.skipped_voxels;
  s.bricks = result.bricks;
  s.brick_halo = result.brick_halo;
  s.seam_mismatches = result.seam_mismatches;
  return s;
}

}  // namespace sheetmesh
