#include "worker/pipeline/surface/mid_surface.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>

#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "worker/pipeline/voxel/components.h"

namespace sheetmesh {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A voxel in a piece's chart frame: (i, j) across the axis, h along it.
struct ChartVoxel {
  int32_t i, j, h;
  bool operator<(const ChartVoxel& o) const {
    return std::tie(i, j, h) < std::tie(o.i, o.j, o.h);
  }
};

// A column's kept run: the voxel centres it spans along the axis, and its two walls, each
// somewhere within the voxel beyond its last centre.
struct Column {
  bool present = false;
  int32_t lo = 0, hi = 0;  // first and last voxel centre of the run
  double wall_lo = 0, wall_hi = 0;
  double mid() const { return 0.5 * (wall_lo + wall_hi); }
  double length() const { return wall_hi - wall_lo; }
};

uint64_t Key(int32_t i, int32_t j) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(i)) << 32) | static_cast<uint32_t>(j);
}

// Coordinates of a voxel in the frame of `axis`: the other two in cyclic order (so that
// (i, j, h) is right-handed), then the axis'.
ChartVoxel InFrame(const Index3& p, int axis) {
  const int32_t c[3] = {p.x, p.y, p.z};
  return {c[(axis + 1) % 3], c[(axis + 2) % 3], c[axis]};
}

Vec3 FromFrame(double i, double j, double h, int axis) {
  double c[3];
  c[(axis + 1) % 3] = i;
  c[(axis + 2) % 3] = j;
  c[axis] = h;
  return Vec3(c[0], c[1], c[2]);
}

// The plane of least squares through a piece's voxels.
void FitPlane(const std::vector<Index3>& voxels, Vec3* centroid, Vec3* normal) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Index3& p : voxels) mean += Eigen::Vector3d(p.x, p.y, p.z);
  mean /= static_cast<double>(voxels.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Index3& p : voxels) {
    const Eigen::Vector3d d = Eigen::Vector3d(p.x, p.y, p.z) - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d n = eig.eigenvectors().col(0);  // the least spread
  *centroid = Vec3(mean.x(), mean.y(), mean.z());
  *normal = Normalized(Vec3(n.x(), n.y(), n.z()));
}

// One piece's height field and its mesh.
class Chart {
 public:
  Chart(std::vector<Index3> voxels, int32_t piece) : voxels_(std::move(voxels)) {
    info_.piece = piece;
    info_.voxels = voxels_.size();
    FitPlane(voxels_, &info_.centroid, &info_.normal);
    const double n[3] = {std::abs(info_.normal.x), std::abs(info_.normal.y),
                         std::abs(info_.normal.z)};
    info_.axis = static_cast<int>(std::max_element(n, n + 3) - n);
  }

  // Appends the chart's vertices and faces to `mesh`.
  void Mesh(TriangleMesh* mesh) {
    Columns();
    SmoothWalls();
    const int axis = info_.axis;
    // Corner (i, j) is the lower corner of column (i, j); corners span one more than columns.
    std::vector<uint32_t> corner(static_cast<size_t>((ni_ + 1) * (nj_ + 1)), UINT32_MAX);
    auto vertex = [&](int32_t i, int32_t j) {
      uint32_t& id = corner[static_cast<size_t>(i * (nj_ + 1) + j)];
      if (id == UINT32_MAX) {
        id = static_cast<uint32_t>(mesh->vertices.size());
        double h = 0, length = 0, gi = 0, gj = 0;
        Corner(i, j, &h, &length, &gi, &gj);
        mesh->vertices.push_back(FromFrame(i0_ + i - 0.5, j0_ + j - 0.5, h, axis));
        // Across the sheet: the walls' distance along the axis times the cosine of the tilt.
        const double cosine = 1 / std::sqrt(1 + gi * gi + gj * gj);
        info_.max_tilt_degrees = std::max(info_.max_tilt_degrees, std::acos(cosine) * 180 / kPi);
        mesh->vertex_thickness_voxels.push_back(static_cast<float>(length * cosine));
      }
      return id;
    };
    for (int32_t i = 0; i < ni_; ++i) {
      for (int32_t j = 0; j < nj_; ++j) {
        if (!At(i, j)) continue;
        const uint32_t a = vertex(i, j), b = vertex(i + 1, j), c = vertex(i + 1, j + 1),
                       d = vertex(i, j + 1);
        // The shorter diagonal.
        if (Norm2(mesh->vertices[a] - mesh->vertices[c]) <=
            Norm2(mesh->vertices[b] - mesh->vertices[d])) {
          mesh->faces.push_back({a, b, c});
          mesh->faces.push_back({a, c, d});
        } else {
          mesh->faces.push_back({a, b, d});
          mesh->faces.push_back({b, c, d});
        }
        mesh->face_piece.push_back(info_.piece);
        mesh->face_piece.push_back(info_.piece);
      }
    }
  }

  const MidSurfaceChart& info() const { return info_; }

 private:
  // Each column's runs; the longest kept (ties: the one nearest the piece's plane), on a
  // grid over the chart's bounding rectangle.
  void Columns() {
    const int axis = info_.axis;
    std::vector<ChartVoxel> v(voxels_.size());
    for (size_t k = 0; k < voxels_.size(); ++k) v[k] = InFrame(voxels_[k], axis);
    voxels_ = {};
    std::sort(v.begin(), v.end());
    i0_ = v.front().i;
    j0_ = v.front().j;
    int32_t i1 = v.back().i, j1 = v.front().j;
    for (const ChartVoxel& p : v) {
      j0_ = std::min(j0_, p.j);
      j1 = std::max(j1, p.j);
    }
    ni_ = i1 - i0_ + 1;
    nj_ = j1 - j0_ + 1;
    grid_.assign(static_cast<size_t>(ni_) * nj_, Column{});
    const double c[3] = {info_.centroid.x, info_.centroid.y, info_.centroid.z};
    const double nn[3] = {info_.normal.x, info_.normal.y, info_.normal.z};
    const double ci = c[(axis + 1) % 3], cj = c[(axis + 2) % 3], ch = c[axis];
    const double ni = nn[(axis + 1) % 3], nj = nn[(axis + 2) % 3], nh = nn[axis];
    for (size_t s = 0; s < v.size();) {
      size_t e = s;
      while (e < v.size() && v[e].i == v[s].i && v[e].j == v[s].j) ++e;
      // The plane's height at this column, to break ties between runs.
      const double plane = ch - (ni * (v[s].i - ci) + nj * (v[s].j - cj)) / nh;
      Column best;
      double best_distance = 0;
      for (size_t r = s; r < e;) {
        size_t q = r + 1;
        while (q < e && v[q].h == v[q - 1].h + 1) ++q;
        Column run;
        run.present = true;
        run.lo = v[r].h;
        run.hi = v[q - 1].h;
        const double distance = std::abs(0.5 * (run.lo + run.hi) - plane);
        if (!best.present || run.hi - run.lo > best.hi - best.lo ||
            (run.hi - run.lo == best.hi - best.lo && distance < best_distance)) {
          best = run;
          best_distance = distance;
        }
        r = q;
      }
      info_.uncovered += (e - s) - static_cast<uint64_t>(best.hi - best.lo + 1);
      Cell(v[s].i - i0_, v[s].j - j0_) = best;
      ++info_.columns;
      s = e;
    }
  }

  // The walls: each lies somewhere in the voxel beyond its run's last centre (the image says
  // no more of where); of those places, the smoothest are taken — each wall averaged with
  // its neighbours' and put back into its voxel, repeatedly (a projection onto the
  // constraints). A plane comes out as the plane, not as the staircase of its voxels; a wall
  // as rough as its voxels stays so.
  void SmoothWalls() {
    constexpr int kRounds = 40;
    constexpr double kMargin = 0.05;  // a wall never quite at a voxel centre
    for (Column& col : grid_) {
      if (!col.present) continue;
      col.wall_lo = col.lo - 0.5;
      col.wall_hi = col.hi + 0.5;
    }
    std::vector<double> lo(grid_.size()), hi(grid_.size());
    for (int round = 0; round < kRounds; ++round) {
      for (int32_t i = 0; i < ni_; ++i) {
        for (int32_t j = 0; j < nj_; ++j) {
          const size_t k = static_cast<size_t>(i) * nj_ + j;
          const Column& col = grid_[k];
          if (!col.present) continue;
          double sl = col.wall_lo, sh = col.wall_hi;
          int n = 1;
          for (const auto& [di, dj] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
            if (const Column* o = At(i + di, j + dj)) {
              sl += o->wall_lo;
              sh += o->wall_hi;
              ++n;
            }
          }
          lo[k] = std::clamp(sl / n, col.lo - 1 + kMargin, col.lo - kMargin);
          hi[k] = std::clamp(sh / n, col.hi + kMargin, col.hi + 1 - kMargin);
        }
      }
      for (size_t k = 0; k < grid_.size(); ++k) {
        if (!grid_[k].present) continue;
        grid_[k].wall_lo = lo[k];
        grid_[k].wall_hi = hi[k];
      }
    }
  }

  Column& Cell(int32_t i, int32_t j) { return grid_[static_cast<size_t>(i) * nj_ + j]; }
  const Column* At(int32_t i, int32_t j) const {
    if (i < 0 || j < 0 || i >= ni_ || j >= nj_) return nullptr;
    const Column& c = grid_[static_cast<size_t>(i) * nj_ + j];
    return c.present ? &c : nullptr;
  }

  // The height, wall distance and slope at corner (i, j) — the lower corner of column
  // (i, j), in grid coordinates. The four columns around it give the height and distance
  // where all are there (the mean of a plane's four values is its value at the corner); the
  // slope, and the height at a rim, come from the plane of least squares through the
  // columns within two of it.
  void Corner(int32_t i, int32_t j, double* h, double* length, double* gi, double* gj) const {
    double sum = 0, len = 0;
    int n = 0;
    for (int di = -1; di <= 0; ++di) {
      for (int dj = -1; dj <= 0; ++dj) {
        if (const Column* col = At(i + di, j + dj)) {
          sum += col->mid();
          len += col->length();
          ++n;
        }
      }
    }
    *length = n > 0 ? len / n : 0;
    // h = a + b di + c dj over the window, at corner offsets (di, dj) = column centre - corner.
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    int count = 0;
    for (int di = -2; di <= 1; ++di) {
      for (int dj = -2; dj <= 1; ++dj) {
        const Column* col = At(i + di, j + dj);
        if (col == nullptr) continue;
        const Eigen::Vector3d x(1, di + 0.5, dj + 0.5);
        A += x * x.transpose();
        b += x * col->mid();
        ++count;
      }
    }
    *gi = *gj = 0;
    double plane = n > 0 ? sum / n : 0;
    if (count >= 3) {
      Eigen::FullPivLU<Eigen::Matrix3d> lu(A);
      if (lu.rank() == 3) {
        const Eigen::Vector3d x = lu.solve(b);
        plane = x(0);
        *gi = x(1);
        *gj = x(2);
      }
    }
    *h = n == 4 ? sum / 4 : plane;
  }

  std::vector<Index3> voxels_;
  MidSurfaceChart info_;
  int32_t i0_ = 0, j0_ = 0, ni_ = 0, nj_ = 0;
  std::vector<Column> grid_;
};

}  // namespace

absl::StatusOr<MidSurface> BuildMidSurface(const VoxelSet& set,
                                           std::span<const int32_t> piece_of_voxel,
                                           const Progress& progress) {
  if (!piece_of_voxel.empty() && piece_of_voxel.size() != set.size()) {
    return absl::InvalidArgumentError(absl::StrCat("mid-surface: ", piece_of_voxel.size(),
                                                   " piece labels for ", set.size(), " voxels"));
  }
  std::vector<int32_t> labels;
  if (piece_of_voxel.empty()) {
    SM_ASSIGN_OR_RETURN(const Components comps, LabelComponents(set, Connectivity::k6));
    const std::vector<uint32_t> l = comps.VoxelLabels(set);
    labels.assign(l.begin(), l.end());
    piece_of_voxel = labels;
  }
  int32_t pieces = 0;
  for (int32_t p : piece_of_voxel) pieces = std::max(pieces, p + 1);
  std::vector<std::vector<Index3>> voxels(pieces);
  set.ForEachVoxel([&](uint64_t index, int32_t x, int32_t y, int32_t z) {
    const int32_t p = piece_of_voxel[index];
    if (p >= 0) voxels[p].push_back({x, y, z});
  });
  MidSurface out;
  for (int32_t p = 0; p < pieces; ++p) {
    SM_RETURN_IF_ERROR(progress.Update(double(p) / std::max(1, pieces)));
    if (voxels[p].size() < 3) continue;
    Chart chart(std::move(voxels[p]), p);
    chart.Mesh(&out.mesh);
    out.charts.push_back(chart.info());
  }
  TriangleMesh& m = out.mesh;
  m.face_thickness_voxels.resize(m.faces.size());
  for (size_t f = 0; f < m.faces.size(); ++f) {
    float t = 0;
    for (uint32_t v : m.faces[f]) t += m.vertex_thickness_voxels[v];
    m.face_thickness_voxels[f] = t / 3;
  }
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return out;
}

}  // namespace sheetmesh
