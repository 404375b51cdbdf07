#include "worker/pipeline/flow/image_permeability.h"

#include <Eigen/Dense>
#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/status_macros.h"

namespace sheetmesh {

absl::StatusOr<ImagePermeability> SolveImagePermeability(
    const VoxelSet& sheet, std::span<const uint16_t> thickness, const Vec3& spacing_m,
    const FlowOptions& options, uint64_t max_cells, const Progress& progress) {
  const absl::Time start = absl::Now();
  SM_RETURN_IF_ERROR(CheckPermeability(options.matrix_permeability, "permeability.matrix"));
  if (thickness.size() != sheet.size()) {
    return absl::InvalidArgumentError(
        absl::StrCat("the image reference needs a thickness per "
                     "sheet voxel: ",
                     thickness.size(), " for ", sheet.size()));
  }
  const Dims& d = sheet.dims();
  const int64_t n[3] = {d.nx, d.ny, d.nz};
  const uint64_t cells = static_cast<uint64_t>(d.num_voxels());
  if (cells > max_cells) {
    return absl::ResourceExhaustedError(
        absl::StrCat("the image reference solves one unknown per voxel and is made up to ",
                     max_cells, " voxels; this volume has ", cells));
  }
  const double h[3] = {spacing_m.x, spacing_m.y, spacing_m.z};
  const double mean_h = std::cbrt(h[0] * h[1] * h[2]);
  // Each cell's permeability: the rock's, or a sheet voxel's cubic law. Where sheets cross,
  // a voxel's thickness (its shortest run along the axes) can be the whole crossing's
  // length (two slabs crossing along y: 96 voxels along the line where they meet), which
  // would make the line a pipe: τ is held to twice the sheets' median.
  std::vector<uint16_t> sorted(thickness.begin(), thickness.end());
  uint16_t cap = 1;
  if (!sorted.empty()) {
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    cap = static_cast<uint16_t>(std::max(1, 2 * sorted[sorted.size() / 2]));
  }
  sorted = {};
  std::vector<double> k(cells, options.matrix_permeability);
  sheet.ForEachVoxel([&](uint64_t i, int32_t x, int32_t y, int32_t z) {
    const double a = std::min(thickness[i], cap) * mean_h;
    k[static_cast<size_t>((int64_t{z} * d.ny + y) * d.nx + x)] =
        std::max(options.matrix_permeability, a * a / 12);
  });
  const int64_t stride[3] = {1, d.nx, d.nx * d.ny};
  auto coord = [&](int64_t c, int axis) { return (c / stride[axis]) % n[axis]; };
  // Face area and transmissibility between two cells along `axis` (harmonic mean), and to
  // the box's face from a cell (half a cell).
  auto area = [&](int axis) { return h[(axis + 1) % 3] * h[(axis + 2) % 3]; };
  auto between = [&](double k1, double k2, int axis) {
    return area(axis) * 2 * k1 * k2 / (h[axis] * (k1 + k2));
  };
  auto to_face = [&](double k1, int axis) { return area(axis) * 2 * k1 / h[axis]; };
  // The pressure −x_d at a point of the box's faces: cell centres at index × h.
  auto position = [&](int64_t c, int axis, int side_axis, int side) {
    const double centre = coord(c, axis) * h[axis];
    if (axis != side_axis) return centre;
    return centre + (side ? 0.5 : -0.5) * h[axis];
  };

  ImagePermeability out;
  out.cells = cells;
  const double volume = n[0] * h[0] * n[1] * h[1] * n[2] * h[2];
  for (int g = 0; g < 3; ++g) {
    SM_RETURN_IF_ERROR(
        progress.Update(0.3 * g, absl::StrCat("image solve ", std::string(1, "xyz"[g]))));
    // A permeameter along g: the pressure −x_g on the two faces across g, no flow through
    // the others (held linear there too, a sheet voxel touching them would carry the
    // imposed gradient across its thickness).
    std::vector<Eigen::Triplet<double>> entries;
    entries.reserve(static_cast<size_t>(cells) * 7);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(cells));
    for (int64_t c = 0; c < static_cast<int64_t>(cells); ++c) {
      double diag = 0;
      for (int axis = 0; axis < 3; ++axis) {
        for (int side = 0; side < 2; ++side) {
          const int64_t at = coord(c, axis);
          const bool inside = side ? at + 1 < n[axis] : at > 0;
          if (inside) {
            const int64_t o = c + (side ? stride[axis] : -stride[axis]);
            const double t = between(k[c], k[o], axis);
            entries.emplace_back(c, o, -t);
            diag += t;
          } else if (axis == g) {
            const double t = to_face(k[c], axis);
            diag += t;
            rhs[c] += t * -position(c, g, axis, side);
          }
        }
      }
      entries.emplace_back(c, c, diag);
    }
    Eigen::SparseMatrix<double> a(static_cast<Eigen::Index>(cells),
                                  static_cast<Eigen::Index>(cells));
    a.setFromTriplets(entries.begin(), entries.end());
    entries = {};
    const double scale = 1.0 / a.diagonal().maxCoeff();
    a *= scale;
    rhs *= scale;
    // Natural ordering: the grid's own is already banded, and a fill-reducing one costs
    // more than the solve on a million cells.
    Eigen::ConjugateGradient<
        Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper,
        Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::NaturalOrdering<int>>>
        cg;
    // A reference good to a few in ten thousand is enough beside a mesh's answer.
    cg.setTolerance(std::max(options.tolerance, 1e-8));
    cg.compute(a);
    if (cg.info() != Eigen::Success) {
      return absl::InternalError("image reference: the preconditioner failed");
    }
    const Eigen::VectorXd p = cg.solve(rhs);
    out.iterations[g] = static_cast<int>(cg.iterations());
    out.residual = std::max(out.residual, cg.error());
    if (cg.info() != Eigen::Success) {
      return absl::InternalError(absl::StrCat("image reference: the pressure along ",
                                              std::string(1, "xyz"[g]), " did not converge (",
                                              cg.error(), ")"));
    }
    // ∫ q_i dV: each face's flux times the spacing across it, half at the box's faces.
    double integral[3] = {0, 0, 0};
    for (int64_t c = 0; c < static_cast<int64_t>(cells); ++c) {
      for (int axis = 0; axis < 3; ++axis) {
        const int64_t at = coord(c, axis);
        if (at + 1 < n[axis]) {
          const int64_t o = c + stride[axis];
          integral[axis] += between(k[c], k[o], axis) * (p[c] - p[o]) * h[axis];
        }
        if (axis != g) continue;
        for (int side = 0; side < 2; ++side) {
          if (side ? at + 1 < n[axis] : at > 0) continue;
          const double pb = -position(c, g, axis, side);
          const double outward = to_face(k[c], axis) * (side ? p[c] - pb : pb - p[c]);
          integral[axis] += 0.5 * outward * h[axis];
        }
      }
    }
    for (int i = 0; i < 3; ++i) out.tensor[i][g] = integral[i] / volume;
  }
  Principal(out.tensor, &out.principal, &out.principal_directions);
  out.seconds = absl::ToDoubleSeconds(absl::Now() - start);
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return out;
}

void CompareToImage(const PermeabilityResult& mesh, ImagePermeability* image) {
  for (int j = 0; j < 3; ++j) {
    const double img = image->tensor[j][j];
    image->mesh_to_image[j] = img > 0 ? mesh.permeameter[j] / img : 0;
  }
}

}  // namespace sheetmesh
