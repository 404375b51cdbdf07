#include "worker/pipeline/tet/volume_mesher.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "absl/container/flat_hash_set.h"
#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "worker/pipeline/core/status_macros.h"
#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {
namespace {

Conformity CheckConformity(const Plc& plc, const TetMesh& mesh) {
  Conformity c;
  c.sheet_triangles = plc.sheet_triangles.size();
  // Every facet face must be a face of a tetrahedron.
  absl::flat_hash_set<std::array<uint32_t, 3>> tet_faces;
  for (const Tet& t : mesh.tets) {
    for (int f = 0; f < 4; ++f) {
      std::array<uint32_t, 3> k = {t[(f + 1) % 4], t[(f + 2) % 4], t[(f + 3) % 4]};
      std::sort(k.begin(), k.end());
      tet_faces.insert(k);
    }
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    std::array<uint32_t, 3> k = mesh.faces[f];
    std::sort(k.begin(), k.end());
    if (!tet_faces.contains(k)) ++c.orphan_faces;
  }
  std::vector<double> covered(plc.sheet_triangles.size(), 0.0);
  std::vector<uint8_t> off_plane(plc.sheet_triangles.size(), 0);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const int64_t t = mesh.face_marker[f] - kFirstSheetMarker;
    if (t < 0 || t >= static_cast<int64_t>(covered.size())) continue;
    const Triangle face = {mesh.nodes[mesh.faces[f][0]], mesh.nodes[mesh.faces[f][1]],
                           mesh.nodes[mesh.faces[f][2]]};
    covered[t] += Area(face);
    const Face& s = plc.sheet_triangles[t];
    const Triangle tri = {plc.vertices[s[0]], plc.vertices[s[1]], plc.vertices[s[2]]};
    const double scale = std::sqrt(Area(tri)) + 1e-300;
    for (const Vec3& p : face) {
      if (std::sqrt(PointTriangleDistance2(p, tri)) > 1e-6 * scale) off_plane[t] = 1;
    }
  }
  for (size_t t = 0; t < covered.size(); ++t) {
    const Face& s = plc.sheet_triangles[t];
    const double area = Area({plc.vertices[s[0]], plc.vertices[s[1]], plc.vertices[s[2]]});
    const double err = std::abs(covered[t] - area) / area;
    c.worst_area_error = std::max(c.worst_area_error, err);
    if (err < 1e-6 && !off_plane[t]) {
      ++c.conforming;
    } else if (c.missing.size() < 20) {
      c.missing.push_back(static_cast<uint32_t>(t));
    }
  }
  return c;
}

}  // namespace

absl::StatusOr<VolumeMeshResult> BuildVolumeMesh(const TriangleMesh& sheets, const Dims& dims,
                                                 const Placement& placement,
                                                 const VolumeMeshOptions& options,
                                                 const Progress& progress) {
  VolumeMeshResult r;
  SM_ASSIGN_OR_RETURN(Plc plc, BuildPlc(sheets, dims, placement, options.plc));
  r.snapped_vertices = plc.snapped_vertices;
  r.merged_vertices = plc.merged_vertices;
  r.dropped_triangles = plc.dropped_triangles;
  r.repaired_triangles = plc.repaired_triangles;
  r.flipped_edges = plc.flipped_edges;
  r.dropped_caps = plc.dropped_caps;
  const Vec3 ext = plc.box_hi - plc.box_lo;
  r.box_volume = std::abs(ext.x * ext.y * ext.z);
  const absl::Time start = absl::Now();
  SM_ASSIGN_OR_RETURN(r.mesh, RunTetgen(plc, options.tetgen, progress.Sub(0, 0.9)));
  r.tetgen_seconds = absl::ToDoubleSeconds(absl::Now() - start);
  SM_RETURN_IF_ERROR(ImproveTetMesh(&r.mesh, plc.box_lo, plc.box_hi, options.improve,
                                    &r.improvement, progress.Sub(0.9, 0.98)));
  r.conformity = CheckConformity(plc, r.mesh);
  if (r.conformity.orphan_faces > 0) {
    return absl::InternalError(absl::StrCat("the volume mesh does not conform: ",
                                            r.conformity.orphan_faces,
                                            " facet faces are faces of no tetrahedron"));
  }
  if (r.conformity.conforming != r.conformity.sheet_triangles) {
    return absl::InternalError(absl::StrCat(
        "the volume mesh does not conform: ",
        r.conformity.sheet_triangles - r.conformity.conforming, " of ",
        r.conformity.sheet_triangles, " sheet triangles are not made of tetrahedron faces (first: ",
        r.conformity.missing.empty() ? -1 : static_cast<int64_t>(r.conformity.missing[0]),
        ", area error ", r.conformity.worst_area_error, ")"));
  }
  r.quality = MeasureQuality(r.mesh);
  if (r.quality.inverted > 0) {
    return absl::InternalError(
        absl::StrCat("the volume mesh has ", r.quality.inverted, " inverted tetrahedra"));
  }
  if (std::abs(r.quality.volume - r.box_volume) > 1e-6 * r.box_volume) {
    return absl::InternalError(absl::StrCat("the tetrahedra's volume ", r.quality.volume,
                                            " differs from the box's ", r.box_volume));
  }
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return r;
}

}  // namespace sheetmesh
