#include "worker/pipeline/surface/grey_apertures.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <vector>

#include "absl/strings/str_cat.h"
#include "worker/pipeline/mesh/triangle_geometry.h"

namespace sheetmesh {

absl::StatusOr<GreyApertureStats> SetGreyApertures(TriangleMesh* mesh, const GreyVolume& grey,
                                                   const GreyLevels& levels,
                                                   const GreyApertureOptions& options) {
  const size_t nf = mesh->faces.size();
  if (mesh->face_thickness_voxels.size() != nf) {
    return absl::InvalidArgumentError(
        absl::StrCat("apertures from grey levels need a thickness per face: ",
                     mesh->face_thickness_voxels.size(), " for ", nf, " faces"));
  }
  if (!(options.psf_sigma_voxels > 0 && options.psf_sigma_voxels <= 8)) {
    return absl::InvalidArgumentError(
        absl::StrCat("grey.psf_sigma = ", options.psf_sigma_voxels, " must be in (0, 8] voxels"));
  }
  GreyApertureStats stats;
  stats.levels = levels;
  if (!levels.problem.empty()) return stats;
  stats.measured = true;
  const std::vector<float> counted = mesh->face_aperture_voxels.size() == nf
                                         ? mesh->face_aperture_voxels
                                         : mesh->face_thickness_voxels;
  std::vector<float> aperture = counted;
  // Beyond the sheet's own half thickness: three point-spread widths and a voxel, where
  // the blurred sheet's grey levels have come back to the rock's.
  const double margin = 3 * options.psf_sigma_voxels + 1;
  stats.window_voxels = margin;
  constexpr double kStep = 0.25;
  constexpr double kEnd = 1.5;  // voxels at each end of the window that give the rock's level
  const double contrast = levels.contrast();
  // Each sheet face's profile across it: four lines (the centroid and the points halfway
  // to the corners) sampled every kStep over [-w, w].
  struct Profile {
    size_t face;
    double area = 0;
    Vec3 centre;
    double w = 0;
    double sum = 0;   // of the samples
    double ends = 0;  // mean of the samples within kEnd of the window's ends
    int samples = 0;
  };
  auto measure = [&](size_t f, double w) {
    Profile p;
    p.face = f;
    const Triangle t = Corners(*mesh, f);
    p.area = Area(t);
    const Vec3 n = UnitNormal(t);
    p.centre = (t[0] + t[1] + t[2]) * (1.0 / 3);
    p.w = w;
    const Vec3 lines[4] = {p.centre, (p.centre + t[0]) * 0.5, (p.centre + t[1]) * 0.5,
                           (p.centre + t[2]) * 0.5};
    int end_samples = 0;
    for (const Vec3& q : lines) {
      for (double s = -w; s <= w + 1e-9; s += kStep) {
        const double v = grey.Sample(q + n * s);
        p.sum += v;
        ++p.samples;
        if (std::abs(s) >= w - kEnd) {
          p.ends += v;
          ++end_samples;
        }
      }
    }
    p.ends /= std::max(1, end_samples);
    return p;
  };
  // The aperture of a profile against the rock's level `rock`.
  auto aperture_of = [&](const Profile& p, double rock) {
    return (rock * p.samples - p.sum) * kStep / (4 * contrast);
  };
  std::vector<size_t> faces;
  for (size_t f = 0; f < nf; ++f) {
    if (!mesh->IsBodyFace(f) && Area(Corners(*mesh, f)) > 0) faces.push_back(f);
  }
  // First the window the face's thickness gives, against the scan's rock level; then one
  // wide enough for the aperture that found (a sheet thicker than its detected band would
  // reach into the window's ends).
  std::vector<Profile> profiles;
  for (size_t f : faces) {
    const Profile first = measure(f, 0.5 * mesh->face_thickness_voxels[f] + margin);
    const double guess = std::max(0.0, aperture_of(first, levels.rock));
    const double w = 0.5 * std::max<double>(mesh->face_thickness_voxels[f], guess) + margin;
    profiles.push_back(w == first.w ? first : measure(f, w));
  }
  // The rock's level about each face: the window ends' levels of the faces within a dozen
  // voxels (a scan's rock level drifts across a sample, and a level off by a thousandth of
  // the contrast biases a sub-voxel aperture by a tenth; one face's ends alone are noisy).
  const double reach = std::max(12.0, 4 * margin);
  std::map<std::array<int64_t, 3>, std::vector<size_t>> grid;
  auto cell = [&](const Vec3& p) {
    return std::array<int64_t, 3>{int64_t(std::floor(p.x / reach)),
                                  int64_t(std::floor(p.y / reach)),
                                  int64_t(std::floor(p.z / reach))};
  };
  for (size_t i = 0; i < profiles.size(); ++i) grid[cell(profiles[i].centre)].push_back(i);
  double sum = 0, sum_counted = 0, area_sum = 0, neighbours = 0, windows = 0;
  for (const Profile& p : profiles) {
    const auto c = cell(p.centre);
    double rock = 0, weight = 0;
    windows += 2 * p.w;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          auto it = grid.find({c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == grid.end()) continue;
          for (size_t j : it->second) {
            if (Norm2(profiles[j].centre - p.centre) > reach * reach) continue;
            rock += profiles[j].area * profiles[j].ends;
            weight += profiles[j].area;
            neighbours += 1;
          }
        }
    // The mean takes the value as measured (noise makes some negative; clipping them would
    // bias it up); a face's aperture is not below 0.
    const double a = aperture_of(p, weight > 0 ? rock / weight : levels.rock);
    aperture[p.face] = static_cast<float>(std::max(0.0, a));
    sum += p.area * a;
    sum_counted += p.area * counted[p.face];
    area_sum += p.area;
    ++stats.faces;
  }
  mesh->face_aperture_voxels = std::move(aperture);
  // The vertices: their faces' mean aperture.
  std::vector<double> vsum(mesh->vertices.size(), 0.0), vn(mesh->vertices.size(), 0.0);
  for (size_t f = 0; f < nf; ++f) {
    for (uint32_t v : mesh->faces[f]) {
      vsum[v] += mesh->face_aperture_voxels[f];
      vn[v] += 1;
    }
  }
  mesh->vertex_thickness_voxels.resize(mesh->vertices.size());
  for (size_t v = 0; v < vsum.size(); ++v) {
    if (vn[v] > 0) mesh->vertex_thickness_voxels[v] = static_cast<float>(vsum[v] / vn[v]);
  }
  if (area_sum > 0) {
    stats.mean_voxels = sum / area_sum;
    stats.counted_mean_voxels = sum_counted / area_sum;
  }
  // One face's standard error from the noise: the noise integrated over its window (about
  // one independent value per voxel of it, four lines), and the error of the rock's level
  // (the ends of the faces around: four lines, two ends, kEnd voxels each), which weighs
  // on the whole window.
  if (!profiles.empty()) {
    const double window = windows / profiles.size();
    const double around = std::max(1.0, neighbours / profiles.size());
    const double integral = std::sqrt(window) / 2;
    const double background = window / std::sqrt(4 * 2 * kEnd * around);
    stats.uncertainty_voxels =
        levels.noise / contrast * std::sqrt(integral * integral + background * background);
  }
  return stats;
}

}  // namespace sheetmesh
