#include "worker/pipeline/surface/mid_surface_chart.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <set>
#include <tuple>

namespace sheetmesh {
namespace {

// The centroid of `points` and the unit eigenvector of their scatter matrix in column k
// (0: the direction of least spread, 2: of most).
Vec3 ScatterAxis(const std::vector<Vec3>& points, int k, Vec3* centroid) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Vec3& p : points) mean += Eigen::Vector3d(p.x, p.y, p.z);
  mean /= static_cast<double>(std::max<size_t>(1, points.size()));
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Vec3& p : points) {
    const Eigen::Vector3d d = Eigen::Vector3d(p.x, p.y, p.z) - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d n = eig.eigenvectors().col(k);
  *centroid = Vec3(mean.x(), mean.y(), mean.z());
  return Normalized(Vec3(n.x(), n.y(), n.z()));
}

}  // namespace

void FitPlanePoints(const std::vector<Vec3>& points, Vec3* centroid, Vec3* normal) {
  *normal = ScatterAxis(points, 0, centroid);
}

void PrincipalLine(const std::vector<Vec3>& points, Vec3* centroid, Vec3* direction) {
  *direction = ScatterAxis(points, 2, centroid);
}

bool ClipToBox(const Vec3& p, const Vec3& u, const Dims& dims, double* t0, double* t1) {
  const double n[3] = {double(dims.nx), double(dims.ny), double(dims.nz)};
  const double pp[3] = {p.x, p.y, p.z}, uu[3] = {u.x, u.y, u.z};
  for (int k = 0; k < 3; ++k) {
    const double lo = -0.5, hi = n[k] - 0.5;
    if (std::abs(uu[k]) < 1e-12) {
      if (pp[k] < lo || pp[k] > hi) return false;
      continue;
    }
    double a = (lo - pp[k]) / uu[k], b = (hi - pp[k]) / uu[k];
    if (a > b) std::swap(a, b);
    *t0 = std::max(*t0, a);
    *t1 = std::min(*t1, b);
  }
  return *t1 > *t0;
}

Chart::Chart(std::vector<Index3> voxels, int32_t piece, const Dims& dims) : dims_(dims) {
  info_.piece = piece;
  info_.voxels = voxels.size();
  if (voxels.empty()) return;
  std::vector<Vec3> points(voxels.size());
  for (size_t k = 0; k < voxels.size(); ++k)
    points[k] = Vec3(voxels[k].x, voxels[k].y, voxels[k].z);
  FitPlanePoints(points, &info_.centroid, &info_.normal);
  const double n[3] = {std::abs(info_.normal.x), std::abs(info_.normal.y),
                       std::abs(info_.normal.z)};
  info_.axis = static_cast<int>(std::max_element(n, n + 3) - n);
  Columns(std::move(voxels));
  SmoothWalls();
  ExtendToBox();
}

Vec3 Chart::Point(double i, double j, double h) const {
  double c[3];
  const int a = info_.axis;
  c[(a + 1) % 3] = i0_ + i;
  c[(a + 2) % 3] = j0_ + j;
  c[a] = h;
  return Vec3(c[0], c[1], c[2]);
}

void Chart::ToGrid(const Vec3& p, double* i, double* j, double* h) const {
  const int a = info_.axis;
  *i = p[(a + 1) % 3] - i0_;
  *j = p[(a + 2) % 3] - j0_;
  *h = p[a];
}

const ChartColumn* Chart::At(int32_t i, int32_t j) const {
  if (i < 0 || j < 0 || i >= ni_ || j >= nj_) return nullptr;
  const ChartColumn& c = grid_[static_cast<size_t>(i) * nj_ + j];
  return c.present ? &c : nullptr;
}

bool Chart::InBox(int32_t i, int32_t j) const {
  const int64_t extent[3] = {dims_.nx, dims_.ny, dims_.nz};
  const int64_t a = i0_ + i, b = j0_ + j;
  return a >= 0 && b >= 0 && a < extent[(info_.axis + 1) % 3] && b < extent[(info_.axis + 2) % 3];
}

int BoxFacesAt(const Vec3& p, const Dims& dims, double within) {
  const double extent[3] = {static_cast<double>(dims.nx), static_cast<double>(dims.ny),
                            static_cast<double>(dims.nz)};
  int faces = 0;
  for (int k = 0; k < 3; ++k) {
    faces += std::abs(p[k] + 0.5) < within;
    faces += std::abs(p[k] - extent[k] + 0.5) < within;
  }
  return faces;
}

bool Chart::OnBoxFace(const Vec3& p) const { return BoxFacesAt(p, dims_, kOnBoxFace) > 0; }

bool Chart::HasAll4(int32_t i, int32_t j) const {
  return At(i - 1, j) && At(i + 1, j) && At(i, j - 1) && At(i, j + 1);
}

// Each column's runs; the longest kept (ties: the one nearest the piece's plane), on a grid
// over the chart's bounding rectangle.
void Chart::Columns(std::vector<Index3> voxels) {
  const int axis = info_.axis;
  std::vector<ChartVoxel> v(voxels.size());
  for (size_t k = 0; k < voxels.size(); ++k) {
    const int32_t c[3] = {voxels[k].x, voxels[k].y, voxels[k].z};
    v[k] = {c[(axis + 1) % 3], c[(axis + 2) % 3], c[axis]};
  }
  voxels = {};
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
  grid_.assign(static_cast<size_t>(ni_) * nj_, ChartColumn{});
  const Vec3& c = info_.centroid;
  const Vec3& n = info_.normal;
  for (size_t s = 0; s < v.size();) {
    size_t e = s;
    while (e < v.size() && v[e].i == v[s].i && v[e].j == v[s].j) ++e;
    // The plane's height at this column, to break ties between runs.
    const Vec3 q = Point(v[s].i - i0_, v[s].j - j0_, 0);
    const double plane = Dot(n, c - q) / n[axis];
    ChartColumn best;
    double best_distance = 0;
    for (size_t r = s; r < e;) {
      size_t t = r + 1;
      while (t < e && v[t].h == v[t - 1].h + 1) ++t;
      ChartColumn run;
      run.present = true;
      run.lo = v[r].h;
      run.hi = v[t - 1].h;
      const double distance = std::abs(0.5 * (run.lo + run.hi) - plane);
      if (!best.present || run.hi - run.lo > best.hi - best.lo ||
          (run.hi - run.lo == best.hi - best.lo && distance < best_distance)) {
        best = run;
        best_distance = distance;
      }
      r = t;
    }
    info_.uncovered += (e - s) - static_cast<uint64_t>(best.hi - best.lo + 1);
    Cell(v[s].i - i0_, v[s].j - j0_) = best;
    ++info_.columns;
    s = e;
  }
}

// The walls: each lies somewhere in the voxel beyond its run's last centre (the image says no
// more of where); of those places, the smoothest are taken — each wall averaged with its
// neighbours' and put back into its voxel, repeatedly (a projection onto the constraints). A
// plane comes out as the plane, not as the staircase of its voxels; a wall as rough as its
// voxels stays so.
void Chart::SmoothWalls() {
  constexpr int kRounds = 40;
  constexpr double kMargin = 0.05;  // a wall never quite at a voxel centre
  for (ChartColumn& col : grid_) {
    if (!col.present) continue;
    col.wall_lo = col.lo - 0.5;
    col.wall_hi = col.hi + 0.5;
  }
  std::vector<double> lo(grid_.size()), hi(grid_.size());
  for (int round = 0; round < kRounds; ++round) {
    for (int32_t i = 0; i < ni_; ++i) {
      for (int32_t j = 0; j < nj_; ++j) {
        const size_t k = static_cast<size_t>(i) * nj_ + j;
        const ChartColumn& col = grid_[k];
        if (!col.present) continue;
        double sl = col.wall_lo, sh = col.wall_hi;
        int n = 1;
        for (const auto& [di, dj] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
          if (const ChartColumn* o = At(i + di, j + dj)) {
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

bool Chart::LocalPlane(const Vec3& a, const Vec3& d, double ta, double tb, double inner,
                       double outer, Vec3* centroid, Vec3* normal, double* thickness) const {
  // Near the contact, and over the whole chart: a chart that is a plane (its mid-points
  // within a voxel of it) takes the whole plane, which the voxels near a shallow junction
  // (where two sheets' runs merge for many voxels) cannot bias; a curved one the local fit.
  std::vector<Vec3> near, all;
  double near_length = 0, all_length = 0;
  for (int32_t i = 0; i < ni_; ++i) {
    for (int32_t j = 0; j < nj_; ++j) {
      const ChartColumn* c = At(i, j);
      if (c == nullptr || c->filled) continue;
      const Vec3 p = Point(i, j, c->mid());
      const double t = std::clamp(Dot(p - a, d), ta, tb);
      const double r2 = Norm2(p - (a + d * t));
      if (r2 < inner * inner) continue;
      all.push_back(p);
      all_length += c->length();
      if (r2 > outer * outer) continue;
      near.push_back(p);
      near_length += c->length();
    }
  }
  if (near.size() < 6) return false;
  Vec3 gc, gn;
  FitPlanePoints(all, &gc, &gn);
  double rms = 0;
  for (const Vec3& p : all) rms += Dot(p - gc, gn) * Dot(p - gc, gn);
  rms = std::sqrt(rms / all.size());
  if (rms < 1.0) {
    *centroid = gc;
    *normal = gn;
  } else {
    FitPlanePoints(near, centroid, normal);
  }
  const double tilt = std::abs((*normal)[info_.axis]);
  *thickness = near_length / near.size() * tilt;
  return true;
}

double Chart::ReachAlong(const Vec3& a, const Vec3& d, double from, double radius, int sign) const {
  double reach = from;
  for (int32_t i = 0; i < ni_; ++i) {
    for (int32_t j = 0; j < nj_; ++j) {
      const ChartColumn* c = At(i, j);
      if (c == nullptr || c->filled) continue;
      const Vec3 p = Point(i, j, c->mid());
      const double t = Dot(p - a, d);
      if (sign * (t - reach) <= 0) continue;
      if (Norm2(p - (a + d * t)) <= radius * radius) reach = t;
    }
  }
  return reach;
}

ChartCut Chart::Trace(const JunctionLine& line, int index, const Vec3& towards) const {
  ChartCut cut;
  cut.junction = index;
  double h = 0, i1 = 0, j1 = 0;
  ToGrid(line.point, &cut.ci, &cut.cj, &h);
  ToGrid(line.point + line.direction, &i1, &j1, &h);
  double di = i1 - cut.ci, dj = j1 - cut.cj;
  const double len = std::hypot(di, dj);
  // A line along the axis has no trace in the grid: every column is on it (not expected: the
  // chart's plane leaves it).
  if (len < 1e-9) di = 1, dj = 0;
  cut.di = di / std::max(len, 1e-9);
  cut.dj = dj / std::max(len, 1e-9);
  cut.ni = -cut.dj;
  cut.nj = cut.di;
  double ti = 0, tj = 0;
  ToGrid(towards, &ti, &tj, &h);
  if (cut.Side(ti, tj) < 0) {
    cut.ni = -cut.ni;
    cut.nj = -cut.nj;
  }
  return cut;
}

double Chart::Gap(const ChartCut& cut, const JunctionLine& line) const {
  double gap = 1e300;
  for (int32_t i = 0; i < ni_; ++i) {
    for (int32_t j = 0; j < nj_; ++j) {
      const ChartColumn* c = At(i, j);
      if (c == nullptr || c->filled) continue;
      const double s = cut.Side(i, j);
      if (s < 0 || s >= gap) continue;
      const double t = Dot(Point(i, j, c->mid()) - line.point, line.direction);
      if (t < line.t0 || t > line.t1) continue;
      gap = s;
    }
  }
  return gap;
}

void Chart::Sides(const ChartCut& cut, uint64_t* kept, uint64_t* beyond) const {
  *kept = *beyond = 0;
  for (int32_t i = 0; i < ni_; ++i) {
    for (int32_t j = 0; j < nj_; ++j) {
      const ChartColumn* c = At(i, j);
      if (c == nullptr || c->filled) continue;
      (cut.Side(i, j) >= 0 ? *kept : *beyond) += 1;
    }
  }
}

bool Chart::AlongLine(const JunctionLine& line, double i, double j, double h) const {
  const double t = Dot(Point(i, j, h) - line.point, line.direction);
  return (t >= line.t0 - 0.5 || OnBoxFace(line.point + line.direction * line.t0)) &&
         (t <= line.t1 + 0.5 || OnBoxFace(line.point + line.direction * line.t1));
}

Chart::StripSides Chart::SidesAlong(const ChartCut& cut, const JunctionLine& line) const {
  StripSides out;
  for (int32_t i = 0; i < ni_; ++i) {
    for (int32_t j = 0; j < nj_; ++j) {
      const ChartColumn* c = At(i, j);
      if (c == nullptr || c->filled || !AlongLine(line, i, j, c->mid())) continue;
      const double s = cut.Side(i, j);
      if (s >= 0) {
        ++out.kept;
      } else {
        ++out.beyond;
        out.farthest_beyond = std::max(out.farthest_beyond, -s);
      }
    }
  }
  return out;
}

std::vector<Index3> Chart::TakeBeyond(const ChartCut& cut) {
  std::vector<Index3> out;
  for (int32_t i = 0; i < ni_; ++i) {
    for (int32_t j = 0; j < nj_; ++j) {
      ChartColumn& c = Cell(i, j);
      if (!c.present || cut.Side(i, j) >= 0) continue;
      if (!c.filled) {
        for (int32_t h = c.lo; h <= c.hi; ++h) {
          const Vec3 p = Point(i, j, h);
          out.push_back({static_cast<int32_t>(std::lround(p.x)),
                         static_cast<int32_t>(std::lround(p.y)),
                         static_cast<int32_t>(std::lround(p.z))});
        }
      }
      c = ChartColumn{};
    }
  }
  return out;
}

void Chart::Grow(int32_t lo_i, int32_t lo_j, int32_t hi_i, int32_t hi_j) {
  const int32_t gi0 = std::min(0, lo_i), gj0 = std::min(0, lo_j);
  const int32_t gni = std::max(ni_ - 1, hi_i) - gi0 + 1, gnj = std::max(nj_ - 1, hi_j) - gj0 + 1;
  if (gi0 == 0 && gj0 == 0 && gni == ni_ && gnj == nj_) return;
  std::vector<ChartColumn> grown(static_cast<size_t>(gni) * gnj);
  for (int32_t i = 0; i < ni_; ++i) {
    for (int32_t j = 0; j < nj_; ++j) {
      grown[static_cast<size_t>(i - gi0) * gnj + (j - gj0)] =
          grid_[static_cast<size_t>(i) * nj_ + j];
    }
  }
  for (ChartCut& c : cuts_) {
    c.ci -= gi0;
    c.cj -= gj0;
  }
  grid_ = std::move(grown);
  i0_ += gi0;
  j0_ += gj0;
  ni_ = gni;
  nj_ = gnj;
}

void Chart::ExtendToBox() {
  constexpr int32_t kFitRadius = 4;  // columns: the neighbourhood a cut-off column's fit takes
  constexpr int kRings = 3;          // columns added beyond the cut-off ones
  constexpr double kBeyond = 4;      // voxels past the face an added column may lie
  const int axis = info_.axis;
  const int64_t extent[3] = {dims_.nx, dims_.ny, dims_.nz};
  const int32_t n = static_cast<int32_t>(extent[axis]);
  const int32_t box_i = static_cast<int32_t>(extent[(axis + 1) % 3]);
  const int32_t box_j = static_cast<int32_t>(extent[(axis + 2) % 3]);
  auto cut_off = [&](const ChartColumn& c) {
    return c.present && !c.filled && (c.lo == 0 || c.hi == n - 1);
  };
  // Each cut-off column's neighbourhood: the plane of its uncut neighbours' mid-points
  // (h = a + b di + c dj about the column) and their mean length.
  struct Fit {
    int32_t i = 0, j = 0;
    double a = 0, b = 0, c = 0, length = 0;
  };
  std::vector<Fit> fits;
  for (int32_t i = 0; i < ni_; ++i) {
    for (int32_t j = 0; j < nj_; ++j) {
      if (!cut_off(Cell(i, j))) continue;
      Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
      Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
      double length = 0;
      int count = 0;
      for (int32_t di = -kFitRadius; di <= kFitRadius; ++di) {
        for (int32_t dj = -kFitRadius; dj <= kFitRadius; ++dj) {
          const ChartColumn* o = At(i + di, j + dj);
          if (o == nullptr || o->filled || cut_off(*o)) continue;
          const Eigen::Vector3d x(1, di, dj);
          A += x * x.transpose();
          rhs += x * o->mid();
          length += o->length();
          ++count;
        }
      }
      if (count < 6) continue;
      Eigen::FullPivLU<Eigen::Matrix3d> lu(A);
      if (lu.rank() < 3) continue;
      const Eigen::Vector3d x = lu.solve(rhs);
      fits.push_back({i, j, x(0), x(1), x(2), length / count});
    }
  }
  if (fits.empty()) return;
  // The cut-off columns: the wall the image shows kept, the one at the box put the sheet's
  // thickness there beyond it.
  for (const Fit& fit : fits) {
    ChartColumn& c = Cell(fit.i, fit.j);
    if (c.lo == 0 && c.hi == n - 1) {
      c.wall_lo = fit.a - 0.5 * fit.length;
      c.wall_hi = fit.a + 0.5 * fit.length;
    } else if (c.lo == 0) {
      c.wall_lo = c.wall_hi - fit.length;
    } else {
      c.wall_hi = c.wall_lo + fit.length;
    }
  }
  const int32_t old_i0 = i0_, old_j0 = j0_;
  Grow(std::max(-i0_, -kRings), std::max(-j0_, -kRings),
       std::min(box_i - 1 - i0_, ni_ - 1 + kRings), std::min(box_j - 1 - j0_, nj_ - 1 + kRings));
  for (Fit& fit : fits) {
    fit.i += old_i0 - i0_;
    fit.j += old_j0 - j0_;
  }
  // Rings of columns beyond them on their fit's plane, towards the face the sheet leaves by:
  // the mesh runs past the box, and the clip to the box ends it on the face.
  std::vector<Fit> front = std::move(fits);
  for (int ring = 0; ring < kRings && !front.empty(); ++ring) {
    std::vector<Fit> next;
    for (const Fit& fit : front) {
      for (const auto& [di, dj] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
        const int32_t a = fit.i + di, b = fit.j + dj;
        if (a < 0 || b < 0 || a >= ni_ || b >= nj_ || At(a, b) != nullptr) continue;
        const double h = fit.a + fit.b * di + fit.c * dj;
        const bool low = h < fit.a && h < 0.5 && h > -0.5 - kBeyond;
        const bool high = h > fit.a && h > n - 1.5 && h < n - 0.5 + kBeyond;
        if (!low && !high) continue;
        ChartColumn& c = Cell(a, b);
        c.present = c.filled = true;
        c.lo = c.hi = static_cast<int32_t>(std::lround(h));
        c.wall_lo = h - 0.5 * fit.length;
        c.wall_hi = h + 0.5 * fit.length;
        Fit moved = fit;
        moved.i = a;
        moved.j = b;
        moved.a = h;
        next.push_back(moved);
      }
    }
    front = std::move(next);
  }
}

void Chart::Cut(const ChartCut& cut, const JunctionLine& line, double band, const Vec3& plane_point,
                const Vec3& plane_normal, double thickness) {
  cuts_.push_back(cut);
  const int axis = info_.axis;
  const double tilt = std::max(0.3, std::abs(plane_normal[axis]));
  auto plane_height = [&](int32_t i, int32_t j) {
    const Vec3 q = Point(i, j, 0);
    return Dot(plane_normal, plane_point - q) / (plane_normal[axis] >= 0 ? tilt : -tilt);
  };
  // The grid grows to take the band along the junction's extent.
  double lo_i = 0, hi_i = ni_ - 1, lo_j = 0, hi_j = nj_ - 1;
  for (const double t : {line.t0, line.t1}) {
    for (const double s : {0.0, band}) {
      double i = 0, j = 0, h = 0;
      ToGrid(line.point + line.direction * t, &i, &j, &h);
      i += s * cut.ni;
      j += s * cut.nj;
      lo_i = std::min(lo_i, std::floor(i));
      hi_i = std::max(hi_i, std::ceil(i));
      lo_j = std::min(lo_j, std::floor(j));
      hi_j = std::max(hi_j, std::ceil(j));
    }
  }
  Grow(static_cast<int32_t>(lo_i), static_cast<int32_t>(lo_j), static_cast<int32_t>(hi_i),
       static_cast<int32_t>(hi_j));
  const ChartCut& here = cuts_.back();
  // Beyond the line along its extent: the other charts' side. Past an end inside the box
  // the sheet goes on (a line ending inside a sheet cuts only its strip).
  for (int32_t i = 0; i < ni_; ++i) {
    for (int32_t j = 0; j < nj_; ++j) {
      const ChartColumn& c = Cell(i, j);
      const double h = c.present ? c.mid() : plane_height(i, j);
      if (here.Side(i, j) < kZipGap && AlongLine(line, i, j, h)) {
        Cell(i, j) = ChartColumn{};
        Cell(i, j).cut_away = true;
      }
    }
  }
  // Up to the line: the band's columns between the chart and the line, grown from the
  // chart's own towards the line, within the junction's extent and the line's own grid box.
  // An end of the line on the box bounds nothing: the box does (the face it ends on need
  // not be across the line).
  const bool open0 = OnBoxFace(line.point + line.direction * line.t0);
  const bool open1 = OnBoxFace(line.point + line.direction * line.t1);
  auto in_extent = [&](int32_t i, int32_t j) {
    const double s = here.Side(i, j);
    if (s < kZipGap || s > band || !InBox(i, j)) return false;
    const Vec3 p = Point(i, j, plane_height(i, j));
    const double t = Dot(p - line.point, line.direction);
    // Short of an end on another line: that line's charts are cut and zipped there.
    const double end0 = line.node0 ? line.t0 + kZipGap : line.t0 - 0.5;
    const double end1 = line.node1 ? line.t1 - kZipGap : line.t1 + 0.5;
    return (open0 || t >= end0) && (open1 || t <= end1);
  };
  std::vector<std::pair<int32_t, int32_t>> front;
  for (int32_t i = 0; i < ni_; ++i) {
    for (int32_t j = 0; j < nj_; ++j) {
      if (At(i, j) && here.Side(i, j) <= band) front.push_back({i, j});
    }
  }
  const double half = 0.5 * thickness / tilt;
  while (!front.empty()) {
    std::vector<std::pair<int32_t, int32_t>> next;
    for (const auto& [i, j] : front) {
      for (const auto& [di, dj] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
        const int32_t a = i + di, b = j + dj;
        if (a < 0 || b < 0 || a >= ni_ || b >= nj_ || At(a, b) || Cell(a, b).cut_away ||
            !in_extent(a, b)) {
          continue;
        }
        // Only towards the line: a filled column is nearer to it than the one it grew from.
        if (here.Side(a, b) > here.Side(i, j) + 1e-9) continue;
        ChartColumn& c = Cell(a, b);
        c.present = c.filled = true;
        const double h = plane_height(a, b);
        c.lo = c.hi = static_cast<int32_t>(std::lround(h));
        c.wall_lo = h - half;
        c.wall_hi = h + half;
        next.push_back({a, b});
      }
    }
    front = std::move(next);
  }
  // Within the band the sheet lies on its plane there: the junction meets it at its angle.
  for (int32_t i = 0; i < ni_; ++i) {
    for (int32_t j = 0; j < nj_; ++j) {
      ChartColumn& c = Cell(i, j);
      if (!c.present || c.filled || here.Side(i, j) > band) continue;
      const double h = plane_height(i, j);
      const double length = std::max(c.length(), 2 * half);
      c.wall_lo = h - 0.5 * length;
      c.wall_hi = h + 0.5 * length;
    }
  }
}

// The height, wall distance and slope at corner (i, j) — the lower corner of column (i, j),
// in grid coordinates. The four columns around it give the height and distance where all
// are there (the mean of a plane's four values is its value at the corner); the slope, and
// the height at a rim, come from the plane of least squares through the columns within two
// of it.
}  // namespace sheetmesh
