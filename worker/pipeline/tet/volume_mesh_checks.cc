#include "worker/pipeline/tet/volume_mesh_checks.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "absl/strings/str_format.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/tet/tet_quality.h"

namespace sheetmesh {
namespace {

absl::flat_hash_set<FaceKey> TetFaces(const TetMesh& mesh) {
  absl::flat_hash_set<FaceKey> faces;
  for (const Tet& t : mesh.tets) {
    for (int f = 0; f < 4; ++f) faces.insert(TetFace(t, f));
  }
  return faces;
}

}  // namespace

bool NodesFollowPlc(const Plc& plc, const TetMesh& mesh, double slack) {
  for (const Face& t : plc.sheet_triangles) {
    for (uint32_t v : t) {
      if (v >= mesh.nodes.size() || !(Norm(mesh.nodes[v] - plc.vertices[v]) <= slack)) {
        return false;
      }
    }
  }
  return true;
}

Conformity CheckConformity(const Plc& plc, const TetMesh& mesh) {
  Conformity c;
  c.sheet_triangles = plc.sheet_triangles.size();
  // Every facet face must be a face of a tetrahedron.
  const absl::flat_hash_set<FaceKey> tet_faces = TetFaces(mesh);
  for (const auto& face : mesh.faces) {
    if (!tet_faces.contains(SortedFace(face[0], face[1], face[2]))) ++c.orphan_faces;
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

uint32_t RederiveFacetFaces(const Plc& plc, TetMesh* mesh) {
  const absl::flat_hash_set<FaceKey> tet_faces = TetFaces(*mesh);
  absl::flat_hash_set<int32_t> broken;
  for (size_t f = 0; f < mesh->faces.size(); ++f) {
    const auto& face = mesh->faces[f];
    if (mesh->face_marker[f] >= kFirstSheetMarker &&
        !tet_faces.contains(SortedFace(face[0], face[1], face[2]))) {
      broken.insert(mesh->face_marker[f]);
    }
  }
  if (broken.empty()) return 0;
  // Every sheet face is derived again: a tetrahedron face whose corners all lie on listed
  // sheet faces belongs to the sheet triangle (among those its corners are listed with)
  // that it lies on. Box faces stay as listed.
  absl::flat_hash_map<uint32_t, std::vector<int32_t>> markers;  // vertex -> sheet markers
  TetMesh kept = *mesh;
  kept.faces.clear();
  kept.face_marker.clear();
  kept.face_piece.clear();
  kept.face_thickness_voxels.clear();
  for (size_t f = 0; f < mesh->faces.size(); ++f) {
    const int32_t marker = mesh->face_marker[f];
    if (marker >= kFirstSheetMarker) {
      for (uint32_t v : mesh->faces[f]) markers[v].push_back(marker);
      continue;
    }
    kept.faces.push_back(mesh->faces[f]);
    kept.face_marker.push_back(marker);
    kept.face_piece.push_back(mesh->face_piece[f]);
    kept.face_thickness_voxels.push_back(mesh->face_thickness_voxels[f]);
  }
  auto AssignToSheet = [&](const FaceKey& k) {
    if (!markers.contains(k[0]) || !markers.contains(k[1]) || !markers.contains(k[2])) return;
    std::vector<int32_t> candidates;
    for (uint32_t v : k) {
      const auto& m = markers.at(v);
      candidates.insert(candidates.end(), m.begin(), m.end());
    }
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    for (int32_t marker : candidates) {
      const size_t t = marker - kFirstSheetMarker;
      const Face& s = plc.sheet_triangles[t];
      const Triangle tri = {plc.vertices[s[0]], plc.vertices[s[1]], plc.vertices[s[2]]};
      const double tol = 1e-6 * (std::sqrt(Area(tri)) + 1e-300);
      bool on = true;
      for (uint32_t v : k) on = on && PointTriangleDistance2(mesh->nodes[v], tri) <= tol * tol;
      if (!on) continue;
      kept.faces.push_back(k);
      kept.face_marker.push_back(marker);
      kept.face_piece.push_back(plc.sheet_piece[t]);
      kept.face_thickness_voxels.push_back(plc.sheet_thickness[t]);
      break;
    }
  };
  // In tetrahedron order, so that the faces come out the same on every run.
  absl::flat_hash_set<FaceKey> seen;
  for (const Tet& t : mesh->tets) {
    for (int f = 0; f < 4; ++f) {
      const FaceKey k = TetFace(t, f);
      if (seen.insert(k).second) AssignToSheet(k);
    }
  }
  *mesh = std::move(kept);
  return static_cast<uint32_t>(broken.size());
}

uint32_t TakeBackSheetMoves(const Plc& plc, double keep_above, VolumeMeshResult* r) {
  TetMesh& m = r->mesh;
  const uint32_t n = static_cast<uint32_t>(std::min(plc.vertices.size(), m.nodes.size()));
  std::vector<uint8_t> held(n, 0), on_sheet(n, 0);
  absl::flat_hash_map<int32_t, int> faces_of_marker;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (m.face_piece[f] >= 0) ++faces_of_marker[m.face_marker[f]];
  }
  for (const Face& t : plc.sheet_triangles) {  // the PLC's sheet vertices (NodesFollowPlc)
    for (uint32_t v : t) {
      if (v < n) on_sheet[v] = 1;
    }
  }
  for (size_t f = 0; f < m.faces.size(); ++f) {
    if (m.face_piece[f] < 0) continue;
    const bool split = faces_of_marker[m.face_marker[f]] > 1;
    for (uint32_t v : m.faces[f]) {
      if (v < n) held[v] |= split;
    }
  }
  std::vector<std::vector<uint32_t>> star(n);
  for (uint32_t t = 0; t < m.tets.size(); ++t) {
    for (uint32_t v : m.tets[t]) {
      if (v < n) star[v].push_back(t);
    }
  }
  auto star_worst = [&](uint32_t v) {
    double w = 1e300;
    for (uint32_t t : star[v]) {
      const Tet& q = m.tets[t];
      w = std::min(w,
                   MinDihedralDegrees(m.nodes[q[0]], m.nodes[q[1]], m.nodes[q[2]], m.nodes[q[3]]));
    }
    return w;
  };
  uint32_t returned = 0;
  for (uint32_t v = 0; v < n; ++v) {
    const Vec3 now = m.nodes[v], anchor = plc.vertices[v];
    if (!on_sheet[v] || now == anchor) continue;
    if (!held[v]) {
      for (const double share : {0.0, 0.25, 0.5, 0.75}) {
        m.nodes[v] = anchor + (now - anchor) * share;
        if (star_worst(v) >= keep_above) break;
        m.nodes[v] = now;
      }
    }
    returned += m.nodes[v] == anchor;
  }
  CountSheetMoves(plc, m, &r->improvement);
  return returned;
}

void CountSheetMoves(const Plc& from, const TetMesh& mesh, TetImproveReport* report) {
  std::vector<uint8_t> on_sheet(from.vertices.size(), 0);
  for (const Face& t : from.sheet_triangles) {
    for (uint32_t v : t) on_sheet[v] = 1;
  }
  uint32_t moved = 0;
  double farthest = 0;
  for (uint32_t v = 0; v < on_sheet.size() && v < mesh.nodes.size(); ++v) {
    const double d = on_sheet[v] ? Norm(mesh.nodes[v] - from.vertices[v]) : 0.0;
    if (!(d > 0)) continue;
    ++moved;
    farthest = std::max(farthest, d);
  }
  report->moved_sheet_vertices = moved;
  report->max_sheet_move = farthest;
}

void SheetVerticesFromMesh(const TetMesh& mesh, Plc* plc) {
  for (const Face& t : plc->sheet_triangles) {
    for (uint32_t v : t) plc->vertices[v] = mesh.nodes[v];
  }
}

AngleWarning DescribeWorst(const TetMesh& mesh, double worst, double aim, double wedge,
                           const Placement& placement) {
  AngleWarning w;
  w.degrees = worst;
  w.aim_degrees = aim;
  size_t at = 0;
  double lowest = 1e300;
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    const Tet& q = mesh.tets[t];
    const double d =
        MinDihedralDegrees(mesh.nodes[q[0]], mesh.nodes[q[1]], mesh.nodes[q[2]], mesh.nodes[q[3]]);
    if (d < lowest) lowest = d, at = t;
  }
  const Tet& q = mesh.tets[at];
  std::vector<uint8_t> on_sheet(mesh.nodes.size(), 0);
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.face_piece[f] < 0) continue;
    for (uint32_t v : mesh.faces[f]) on_sheet[v] = 1;
  }
  Vec3 centre(0, 0, 0);
  for (uint32_t v : q) {
    centre += mesh.nodes[v] * 0.25;
    w.corners_on_sheets += on_sheet[v];
  }
  w.at = centre;
  for (int k = 0; k < 3; ++k)
    w.at_voxel[k] = (centre[k] - placement.origin[k]) / placement.spacing[k];
  constexpr double kWedgeTolerance = 1e-6;  // degrees
  if (worst >= wedge - kWedgeTolerance) {
    w.cause = absl::StrFormat(
        "two facets of the input meet there at %.2f degrees (sheets, or a sheet and the box): no "
        "conforming mesh does better (plc.wedge_degrees opens such wedges up to plc.wedge_voxels, "
        "and at junctions up to plc.junction_voxels)",
        wedge);
  } else if (w.corners_on_sheets >= 3) {
    w.cause = absl::StrFormat(
        "%d of its corners are on the sheets, which hold them (a near contact, or a flat gap "
        "framed by sheet edges, as the sheets' triangles at this r leave it)",
        w.corners_on_sheets);
  } else {
    w.cause = "the improvement found nothing better there within improve.passes";
  }
  return w;
}

}  // namespace sheetmesh
