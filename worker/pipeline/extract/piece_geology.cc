#include "worker/pipeline/extract/piece_geology.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <map>

#include "absl/strings/str_format.h"
#include "common/orientation.h"
#include "worker/pipeline/mesh/mesh_io.h"
#include "worker/pipeline/mesh/triangle_geometry.h"
#include "worker/pipeline/similarity/face_attributes.h"

namespace sheetmesh {

std::vector<PieceGeology> ComputePieceGeology(const LabelledVoxels& model,
                                              std::span<const uint16_t> thickness,
                                              const TriangleMesh& mesh, const Placement& pl) {
  struct Acc {
    uint64_t n = 0;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
    double tau_sum = 0;
    uint16_t tau_max = 0;
  };
  std::map<int32_t, Acc> acc;
  model.set.ForEachVoxel([&](uint64_t i, int32_t x, int32_t y, int32_t z) {
    Acc& a = acc[model.label[i]];
    const Vec3 p = pl.ToPhysical(Vec3(x, y, z));
    const Eigen::Vector3d v(p.x, p.y, p.z);
    ++a.n;
    a.sum += v;
    a.outer += v * v.transpose();
    a.tau_sum += thickness[i];
    a.tau_max = std::max(a.tau_max, thickness[i]);
  });
  std::map<int32_t, std::pair<uint64_t, double>> faces;  // triangles, area
  const Vec3 scale = pl.spacing;
  for (size_t f = 0; f < mesh.faces.size() && mesh.face_piece.size() == mesh.faces.size(); ++f) {
    Triangle t = Corners(mesh, f);
    for (Vec3& c : t) c = {c.x * scale.x, c.y * scale.y, c.z * scale.z};
    auto& e = faces[mesh.face_piece[f]];
    ++e.first;
    e.second += Area(t);
  }
  std::vector<PieceGeology> out;
  for (const auto& [label, a] : acc) {
    PieceGeology g;
    g.piece = label;
    g.voxels = a.n;
    const Eigen::Vector3d mean = a.sum / double(a.n);
    g.centroid = {mean.x(), mean.y(), mean.z()};
    const Eigen::Matrix3d cov = a.outer / double(a.n) - mean * mean.transpose();
    // The normal of the least-squares plane: the eigenvector of the smallest eigenvalue.
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    const Eigen::Vector3d n = eig.eigenvectors().col(0);
    g.normal = Normalized(Vec3(n.x(), n.y(), n.z()));
    if (g.normal.z < 0) g.normal = -g.normal;
    const Eigen::Vector3d lambda = eig.eigenvalues();
    g.planarity = lambda(1) > 0 ? 1.0 - lambda(0) / lambda(1) : 0.0;
    const Orientation o = OrientationOf(g.normal);
    g.dip_degrees = o.dip_degrees;
    g.dip_direction_degrees = o.dip_direction_degrees;
    // τ is the shortest axis run; along the plane normal a slab is that times max |n_k|.
    const double factor = AxisRunToNormalFactor(g.normal);
    g.mean_aperture = PhysicalLength(factor * a.tau_sum / a.n, pl);
    g.max_aperture = PhysicalLength(factor * a.tau_max, pl);
    auto it = faces.find(label);
    if (it != faces.end()) {
      g.triangles = it->second.first;
      g.area = it->second.second;
    }
    out.push_back(g);
  }
  AssignSheets(&out);
  return out;
}

namespace {

// Whether pieces a and b lie in one plane: normals within kSheetAngleDegrees, each centroid
// within half their apertures together of the other's plane, and at least one of them
// planar enough for its normal to mean something.
bool OnePlane(const PieceGeology& a, const PieceGeology& b) {
  // A small piece cut near a crossing is often not planar itself; it joins a planar one.
  if (a.planarity < kSheetMinPlanarity && b.planarity < kSheetMinPlanarity) return false;
  if (AngleBetweenNormalsDegrees(a.normal, b.normal) > kSheetAngleDegrees) return false;
  const double tolerance = 0.5 * (a.max_aperture + b.max_aperture);
  const Vec3 d = b.centroid - a.centroid;
  return std::abs(Dot(d, a.normal)) <= tolerance && std::abs(Dot(d, b.normal)) <= tolerance;
}

}  // namespace

void AssignSheets(std::vector<PieceGeology>* pieces) {
  std::vector<PieceGeology>& p = *pieces;
  std::vector<size_t> root(p.size());
  for (size_t i = 0; i < p.size(); ++i) root[i] = i;
  auto find = [&](size_t i) {
    while (root[i] != i) i = root[i] = root[root[i]];
    return i;
  };
  for (size_t i = 0; i < p.size(); ++i) {
    for (size_t j = i + 1; j < p.size(); ++j) {
      if (OnePlane(p[i], p[j])) root[std::max(find(i), find(j))] = std::min(find(i), find(j));
    }
  }
  // Sheets numbered in the order of their first piece (pieces are ordered by label).
  std::map<size_t, int32_t> sheet_of_root;
  for (size_t i = 0; i < p.size(); ++i) {
    auto [it, fresh] = sheet_of_root.try_emplace(find(i), int32_t(sheet_of_root.size()));
    p[i].sheet = it->second;
  }
}

std::string PieceGeologyCsv(const std::vector<PieceGeology>& pieces) {
  std::string out =
      "piece,voxels,triangles,area,mean_aperture,max_aperture,normal_x,normal_y,normal_z,"
      "dip,dip_direction,planarity,centroid_x,centroid_y,centroid_z,sheet\n";
  for (const PieceGeology& g : pieces) {
    absl::StrAppendFormat(
        &out, "%d,%d,%d,%.6g,%.6g,%.6g,%.6f,%.6f,%.6f,%.3f,%.3f,%.4f,%.6g,%.6g,%.6g,%d\n", g.piece,
        g.voxels, g.triangles, g.area, g.mean_aperture, g.max_aperture, g.normal.x, g.normal.y,
        g.normal.z, g.dip_degrees, g.dip_direction_degrees, g.planarity, g.centroid.x, g.centroid.y,
        g.centroid.z, g.sheet);
  }
  return out;
}

void UseFaceApertures(const TriangleMesh& mesh, const Placement& placement,
                      std::vector<PieceGeology>* pieces) {
  const size_t nf = mesh.faces.size();
  if (mesh.face_aperture_voxels.size() != nf || mesh.face_piece.size() != nf) return;
  std::map<int32_t, std::array<double, 3>> by_piece;  // area, area × aperture, largest
  for (size_t f = 0; f < nf; ++f) {
    const double area = Area(Corners(mesh, f));
    auto& s = by_piece[mesh.face_piece[f]];
    s[0] += area;
    s[1] += area * mesh.face_aperture_voxels[f];
    s[2] = std::max<double>(s[2], mesh.face_aperture_voxels[f]);
  }
  for (PieceGeology& g : *pieces) {
    auto it = by_piece.find(g.piece);
    if (it == by_piece.end() || !(it->second[0] > 0)) continue;
    g.mean_aperture = PhysicalLength(it->second[1] / it->second[0], placement);
    g.max_aperture = PhysicalLength(it->second[2], placement);
  }
}

}  // namespace sheetmesh
