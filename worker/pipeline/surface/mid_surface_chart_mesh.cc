// A chart's triangles: a vertex per column corner at its walls' middle, two triangles per
// cell, its rim facing a junction zipped to the line's samples.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <set>
#include <utility>
#include <vector>

#include "worker/pipeline/surface/mid_surface_chart.h"

namespace sheetmesh {

void Chart::Corner(int32_t i, int32_t j, double* h, double* length, double* gi, double* gj) const {
  double sum = 0, len = 0;
  int n = 0;
  for (int di = -1; di <= 0; ++di) {
    for (int dj = -1; dj <= 0; ++dj) {
      if (const ChartColumn* col = At(i + di, j + dj)) {
        sum += col->mid();
        len += col->length();
        ++n;
      }
    }
  }
  *length = n > 0 ? len / n : 0;
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  int count = 0;
  for (int di = -2; di <= 1; ++di) {
    for (int dj = -2; dj <= 1; ++dj) {
      const ChartColumn* col = At(i + di, j + dj);
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

void Chart::Mesh(std::vector<JunctionLine>* lines, TriangleMesh* mesh) {
  std::vector<uint32_t> corner(static_cast<size_t>((ni_ + 1) * (nj_ + 1)), UINT32_MAX);
  auto regular = [&](int32_t i, int32_t j) {
    uint32_t& id = corner[static_cast<size_t>(i) * (nj_ + 1) + j];
    if (id == UINT32_MAX) {
      id = static_cast<uint32_t>(mesh->vertices.size());
      double h = 0, length = 0, gi = 0, gj = 0;
      Corner(i, j, &h, &length, &gi, &gj);
      mesh->vertices.push_back(Point(i - 0.5, j - 0.5, h));
      // Across the sheet: the walls' distance along the axis times the cosine of the tilt.
      const double cosine = 1 / std::sqrt(1 + gi * gi + gj * gj);
      info_.max_tilt_degrees =
          std::max(info_.max_tilt_degrees, std::acos(cosine) * 180 / std::numbers::pi);
      mesh->vertex_thickness_voxels.push_back(static_cast<float>(length * cosine));
    }
    return id;
  };
  auto emit = [&](uint32_t a, uint32_t b, uint32_t c) {
    mesh->faces.push_back({a, b, c});
    mesh->face_piece.push_back(info_.piece);
  };
  for (int32_t i = 0; i < ni_; ++i) {
    for (int32_t j = 0; j < nj_; ++j) {
      if (!At(i, j)) continue;
      // Counter-clockwise in (i, j): normals towards +axis.
      const uint32_t a = regular(i, j), b = regular(i + 1, j), c = regular(i + 1, j + 1),
                     d = regular(i, j + 1);
      if (Norm2(mesh->vertices[a] - mesh->vertices[c]) <=
          Norm2(mesh->vertices[b] - mesh->vertices[d])) {
        emit(a, b, c);
        emit(a, c, d);
      } else {
        emit(a, b, d);
        emit(b, c, d);
      }
    }
  }
  // Each cut's line is zipped to the chart's rim facing it: the rim's corners along the line
  // (a staircase that runs the line's way, so its corners come in order along it) and the
  // line's samples over the same stretch, joined by a strip of triangles, each taking the
  // shorter of the two next diagonals.
  for (const ChartCut& cut : cuts_) {
    JunctionLine& line = (*lines)[cut.junction];
    if (line.vertex_of.empty()) line.vertex_of.assign(line.samples(), UINT32_MAX);
    auto sample = [&](int k) {
      uint32_t& id = line.vertex_of[k];
      if (id == UINT32_MAX) {
        id = static_cast<uint32_t>(mesh->vertices.size());
        mesh->vertices.push_back(line.At(k));
        double t = 0;
        for (double v : line.thickness) t += v;
        mesh->vertex_thickness_voxels.push_back(
            static_cast<float>(line.thickness.empty() ? 0 : t / line.thickness.size()));
      }
      return id;
    };
    // Rim edges facing the line: the column across them is missing and nearer the line. Each
    // runs counter-clockwise around its column, so they link head to tail into chains along
    // the rim.
    std::map<std::pair<int32_t, int32_t>, std::pair<int32_t, int32_t>> next_corner;
    std::set<std::pair<int32_t, int32_t>> heads;
    for (int32_t i = 0; i < ni_; ++i) {
      for (int32_t j = 0; j < nj_; ++j) {
        if (!At(i, j) || cut.Side(i, j) > kZipReach) continue;
        // (neighbour, edge from, edge to): below, right, above, left.
        const std::array<std::array<int32_t, 6>, 4> sides = {{{i, j - 1, i, j, i + 1, j},
                                                              {i + 1, j, i + 1, j, i + 1, j + 1},
                                                              {i, j + 1, i + 1, j + 1, i, j + 1},
                                                              {i - 1, j, i, j + 1, i, j}}};
        for (const auto& e : sides) {
          if (At(e[0], e[1]) || cut.Side(e[0], e[1]) >= cut.Side(i, j) || !InBox(e[0], e[1])) {
            continue;
          }
          next_corner[{e[2], e[3]}] = {e[4], e[5]};
          heads.insert({e[4], e[5]});
        }
      }
    }
    for (const auto& [start, unused] : next_corner) {
      if (heads.count(start) != 0) continue;         // inside a chain
      std::vector<std::pair<double, uint32_t>> rim;  // (t, vertex) along the chain
      auto at = start;
      for (size_t guard = 0; guard <= next_corner.size(); ++guard) {
        const uint32_t v = regular(at.first, at.second);
        rim.push_back({Dot(mesh->vertices[v] - line.point, line.direction), v});
        const auto it = next_corner.find(at);
        if (it == next_corner.end()) break;
        at = it->second;
      }
      ZipToLine(rim, line, sample, emit, mesh);
    }
  }
}

void Chart::ZipToLine(std::vector<std::pair<double, uint32_t>> rim, const JunctionLine& line,
                      const std::function<uint32_t(int)>& sample,
                      const std::function<void(uint32_t, uint32_t, uint32_t)>& emit,
                      TriangleMesh* mesh) const {
  if (rim.size() < 2) return;
  // Only the stretch of the rim along the line is zipped to it: where a junction ends inside
  // the box (a sheet that ends on another, or sheets that curve apart), the rim beyond its
  // end stays open rather than fanning to the end sample over the chart's own columns.
  // So does a rim that lies off the line (a curved sheet whose trace of a straight junction
  // runs away from it): the strip spans only the gap the cut left.
  // At an end on another line the rim's corner there is that line's to zip (zipped to both,
  // the two strips folded over each other).
  const double reach = line.step + 1.0;
  const double from = line.node0 ? line.t0 + kZipGap : line.t0 - reach;
  const double to = line.node1 ? line.t1 - kZipGap : line.t1 + reach;
  auto along = [&](const std::pair<double, uint32_t>& e) {
    if (e.first < from || e.first > to) return false;
    return line.Distance2(mesh->vertices[e.second]) <= kZipSpan * kZipSpan;
  };
  if (!std::all_of(rim.begin(), rim.end(), along)) {
    for (size_t a = 0; a < rim.size();) {
      size_t b = a;
      while (b < rim.size() && along(rim[b])) ++b;
      if (b - a >= 2) {
        ZipToLine({rim.begin() + static_cast<std::ptrdiff_t>(a),
                   rim.begin() + static_cast<std::ptrdiff_t>(b)},
                  line, sample, emit, mesh);
      }
      a = b + 1;
    }
    return;
  }
  // The chain runs as the chart's faces' boundary edges do; the strip takes each such edge
  // reversed. Along the line the chain may run either way.
  const bool reversed = rim.front().first > rim.back().first;
  if (reversed) std::reverse(rim.begin(), rim.end());
  int k0 = std::clamp(static_cast<int>(std::ceil((rim.front().first - line.t0) / line.step)), 0,
                      line.samples() - 1);
  int k1 = std::clamp(static_cast<int>(std::floor((rim.back().first - line.t0) / line.step)), 0,
                      line.samples() - 1);
  // Where the line ends on the box, the sheets meet the face there: a rim that stops short of
  // the end by less than a step and a voxel (its last column's corner) runs on to it, so the
  // junction reaches the face rather than ending a fraction of a voxel inside, beside the
  // rim's own vertex on the face (a needle the volume mesh keeps as a sliver).
  const int last = line.samples() - 1;
  if (k0 > 0 && OnBoxFace(line.At(0)) && rim.front().first - line.t0 <= line.step + 1.0) k0 = 0;
  if (k1 < last && OnBoxFace(line.At(last)) && line.t1 - rim.back().first <= line.step + 1.0) {
    k1 = last;
  }
  if (k1 < k0) return;
  // The strip, oriented as the chart's faces are: (rim r + 1, rim r, sample) on the chain's
  // own run.
  auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
    const Vec3 n =
        Cross(mesh->vertices[b] - mesh->vertices[a], mesh->vertices[c] - mesh->vertices[a]);
    if (Norm2(n) < 1e-12) return;
    if (reversed) std::swap(b, c);
    emit(b, a, c);
  };
  size_t r = 0;
  int k = k0;
  // The ends: the rim's corners before the first sample fan to it, and after the last.
  while (r + 1 < rim.size() && rim[r + 1].first <= line.t0 + k0 * line.step) {
    add(rim[r].second, rim[r + 1].second, sample(k0));
    ++r;
  }
  while (r + 1 < rim.size() || k < k1) {
    const bool can_rim = r + 1 < rim.size(), can_line = k < k1;
    bool take_rim = can_rim;
    if (can_rim && can_line) {
      // The shorter diagonal: rim[r + 1] to sample k, or rim[r] to sample k + 1.
      const double dr = Norm2(mesh->vertices[rim[r + 1].second] - line.At(k));
      const double dl = Norm2(mesh->vertices[rim[r].second] - line.At(k + 1));
      take_rim = dr <= dl;
    }
    if (take_rim) {
      add(rim[r].second, rim[r + 1].second, sample(k));
      ++r;
    } else {
      add(rim[r].second, sample(k + 1), sample(k));
      ++k;
    }
  }
}

}  // namespace sheetmesh
