#include "worker/pipeline/flow/permeability.h"

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
namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;

}  // namespace

absl::Status CheckPermeability(double k, const char* field) {
  if (!(std::isfinite(k) && k > 0 && k <= 1e-3)) {
    return absl::InvalidArgumentError(
        absl::StrCat(field, " = ", k,
                     " m²: a permeability must be positive and at most 1e-3 m² (about 1e9 darcy)"));
  }
  return absl::OkStatus();
}

namespace {

// A linear element: its nodes, the gradients of their shape functions (constant over it),
// its measure (volume or area, metres) and its conductivity (k for a tetrahedron, a³/12 for
// a sheet face); `kind` 0 rock, 1 sheet, 2 body.
template <int N>
struct Element {
  std::array<uint32_t, N> nodes;
  std::array<Vec3, N> gradient;
  double measure = 0;
  double conductivity = 0;
  double velocity = 0;  // what times −∇p is its Darcy velocity × viscosity (k; a²/12 on a sheet)
  size_t cell = 0;      // its cell in volume.vtu: the tetrahedra, then the faces
  int kind = 0;
};

// The gradients of a tetrahedron's shape functions, and its volume; false when degenerate.
bool TetGradients(const std::array<Vec3, 4>& x, std::array<Vec3, 4>* g, double* volume) {
  Eigen::Matrix3d j;
  for (int k = 0; k < 3; ++k) {
    const Vec3 e = x[k + 1] - x[0];
    j.col(k) << e.x, e.y, e.z;
  }
  const double det = j.determinant();
  if (!(std::abs(det) > 0)) return false;
  const Eigen::Matrix3d inv = j.inverse();  // row k: the gradient of node k + 1's function
  Vec3 sum;
  for (int k = 0; k < 3; ++k) {
    (*g)[k + 1] = Vec3(inv(k, 0), inv(k, 1), inv(k, 2));
    sum += (*g)[k + 1];
  }
  (*g)[0] = -sum;
  *volume = std::abs(det) / 6;
  return true;
}

// The in-plane gradients of a triangle's shape functions, and its area; false when
// degenerate.
bool TriangleGradients(const std::array<Vec3, 3>& x, std::array<Vec3, 3>* g, double* area) {
  const Vec3 n = Cross(x[1] - x[0], x[2] - x[0]);
  const double twice = Norm(n);
  if (!(twice > 0)) return false;
  const Vec3 unit = n / twice;
  for (int k = 0; k < 3; ++k) {
    (*g)[k] = Cross(unit, x[(k + 2) % 3] - x[(k + 1) % 3]) / twice;
  }
  *area = twice / 2;
  return true;
}

}  // namespace

void Principal(const Tensor3& t, std::array<double, 3>* values, std::array<Vec3, 3>* directions) {
  Eigen::Matrix3d sym;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) sym(i, j) = 0.5 * (t[i][j] + t[j][i]);
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(sym);
  for (int k = 0; k < 3; ++k) {
    (*values)[k] = es.eigenvalues()[2 - k];
    const Eigen::Vector3d v = es.eigenvectors().col(2 - k);
    (*directions)[k] = Vec3(v[0], v[1], v[2]);
  }
}

absl::StatusOr<PermeabilityResult> SolvePermeability(const TetMesh& mesh,
                                                     const FlowOptions& options,
                                                     const Progress& progress,
                                                     VolumeFields* fields) {
  const absl::Time start = absl::Now();
  SM_RETURN_IF_ERROR(CheckPermeability(options.matrix_permeability, "permeability.matrix"));
  if (options.body_permeability != 0) {
    SM_RETURN_IF_ERROR(CheckPermeability(options.body_permeability, "permeability.body"));
  }
  if (!(options.tolerance > 0 && options.tolerance <= 1e-2)) {
    return absl::InvalidArgumentError(
        absl::StrCat("flow tolerance ", options.tolerance, ": must be in (0, 0.01]"));
  }
  if (mesh.tets.empty() || mesh.nodes.size() < 4) {
    return absl::InvalidArgumentError("flow needs a volume mesh: this one has no tetrahedra");
  }
  PermeabilityResult out;
  out.metres_per_unit = MetresPerUnit(mesh.unit);
  if (out.metres_per_unit == 0) {
    return absl::InvalidArgumentError(absl::StrCat(
        "flow needs the volume's length unit to give a permeability in m², and this volume's is ",
        mesh.unit.empty() ? std::string("not known") : absl::StrCat("\"", mesh.unit, "\""),
        ": give input.unit (", kKnownLengthUnits,
        ") and input.spacing, e.g. --unit=um "
        "--spacing=5,5,5"));
  }
  const double m = out.metres_per_unit;
  const size_t n = mesh.nodes.size();
  std::vector<Vec3> x(n);
  Vec3 lo = mesh.nodes[0] * m, hi = lo;
  for (size_t i = 0; i < n; ++i) {
    x[i] = mesh.nodes[i] * m;
    lo = Vec3(std::min(lo.x, x[i].x), std::min(lo.y, x[i].y), std::min(lo.z, x[i].z));
    hi = Vec3(std::max(hi.x, x[i].x), std::max(hi.y, x[i].y), std::max(hi.z, x[i].z));
  }
  const Vec3 extent = hi - lo;
  out.volume = extent.x * extent.y * extent.z;
  if (!(out.volume > 0)) {
    return absl::InvalidArgumentError("flow: the volume mesh's box has no volume");
  }

  // Each body's permeability: the one given, or a²/12 of its thickness a = 2 V / A.
  if (!mesh.body_pieces.empty()) {
    std::map<int32_t, double> volume, area;
    for (size_t t = 0; t < mesh.tets.size(); ++t) {
      const int32_t p = mesh.Region(t);
      if (p < 0) continue;
      const Tet& q = mesh.tets[t];
      volume[p] += std::abs(TetVolume(x[q[0]], x[q[1]], x[q[2]], x[q[3]]));
    }
    for (size_t f = 0; f < mesh.faces.size(); ++f) {
      const int32_t p = mesh.face_piece[f];
      if (p < 0 || !mesh.IsBody(p)) continue;
      const auto& q = mesh.faces[f];
      area[p] += 0.5 * Norm(Cross(x[q[1]] - x[q[0]], x[q[2]] - x[q[0]]));
    }
    for (int32_t p : mesh.body_pieces) {
      double k = options.body_permeability;
      if (k == 0 && area[p] > 0) {
        const double a = 2 * volume[p] / area[p];
        k = std::max(options.matrix_permeability, a * a / 12);
      }
      out.body_permeability[p] = k > 0 ? k : options.matrix_permeability;
    }
  }

  // The elements.
  std::vector<Element<4>> tets;
  tets.reserve(mesh.tets.size());
  for (size_t t = 0; t < mesh.tets.size(); ++t) {
    Element<4> e;
    e.nodes = mesh.tets[t];
    std::array<Vec3, 4> p;
    for (int k = 0; k < 4; ++k) p[k] = x[e.nodes[k]];
    if (!TetGradients(p, &e.gradient, &e.measure)) continue;
    e.kind = mesh.Region(t) >= 0 ? 2 : 0;
    e.conductivity =
        e.kind == 2 ? out.body_permeability.at(mesh.Region(t)) : options.matrix_permeability;
    e.velocity = e.conductivity;
    e.cell = t;
    out.body_tets += e.kind == 2;
    tets.push_back(e);
  }
  std::vector<Element<3>> faces;
  uint64_t closed = 0;  // sheet faces of aperture 0 (over holes)
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.face_marker[f] < 10 || mesh.face_piece[f] < 0 || mesh.IsBody(mesh.face_piece[f])) {
      continue;
    }
    const double a = mesh.FaceThickness(f) * m;
    if (!(std::isfinite(a) && a >= 0)) {
      return absl::InvalidArgumentError(
          absl::StrCat("flow: sheet face ", f, " (piece ", mesh.face_piece[f], ") has aperture ", a,
                       " m: an aperture must be finite and not negative"));
    }
    if (a == 0) {
      ++closed;
      continue;
    }
    Element<3> e;
    for (int k = 0; k < 3; ++k) e.nodes[k] = mesh.faces[f][k];
    if (!TriangleGradients({x[e.nodes[0]], x[e.nodes[1]], x[e.nodes[2]]}, &e.gradient,
                           &e.measure)) {
      continue;
    }
    e.kind = 1;
    e.conductivity = a * a * a / 12;  // the local cubic law: transmissivity per unit viscosity
    e.velocity = a * a / 12;
    e.cell = mesh.tets.size() + f;
    faces.push_back(e);
  }
  out.sheet_faces = faces.size();

  // Which side of the box a node lies on: bit 2d for the face at the least x_d, 2d + 1 the
  // greatest.
  const double eps = 1e-9 * std::max({extent.x, extent.y, extent.z});
  std::vector<uint8_t> sides(n, 0);
  for (size_t i = 0; i < n; ++i) {
    for (int d = 0; d < 3; ++d) {
      if ((&x[i].x)[d] - (&lo.x)[d] <= eps) sides[i] |= uint8_t(1) << (2 * d);
      if ((&hi.x)[d] - (&x[i].x)[d] <= eps) sides[i] |= uint8_t(1) << (2 * d + 1);
    }
  }
  // The pressure of axis d at a fixed node: −x_d (a unit gradient along −d drives flow
  // along +d).
  auto fixed_pressure = [&](size_t i, int d) { return -(&x[i].x)[d]; };

  // One solve along d with the pressure held on the nodes whose sides meet `held`: the
  // pressure at every node.
  auto solve = [&](uint8_t held, int d, double* residual, int* iterations,
                   uint64_t* unknowns) -> absl::StatusOr<Eigen::VectorXd> {
    std::vector<int64_t> unknown(n, -1);
    uint64_t count = 0;
    for (size_t i = 0; i < n; ++i) {
      if (!(sides[i] & held)) unknown[i] = static_cast<int64_t>(count++);
    }
    if (unknowns) *unknowns = count;
    Eigen::VectorXd pressure(static_cast<Eigen::Index>(n));
    for (size_t i = 0; i < n; ++i) pressure[static_cast<Eigen::Index>(i)] = fixed_pressure(i, d);
    if (count == 0) return pressure;
    std::vector<Eigen::Triplet<double>> entries;
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(count));
    auto assemble = [&](const auto& e) {
      constexpr int N = std::tuple_size_v<decltype(e.nodes)>;
      const double w = e.measure * e.conductivity;
      for (int a = 0; a < N; ++a) {
        const int64_t ua = unknown[e.nodes[a]];
        if (ua < 0) continue;
        for (int b = 0; b < N; ++b) {
          const double kab = w * Dot(e.gradient[a], e.gradient[b]);
          const int64_t ub = unknown[e.nodes[b]];
          if (ub >= 0) {
            entries.emplace_back(ua, ub, kab);
          } else {
            rhs[ua] -= kab * fixed_pressure(e.nodes[b], d);
          }
        }
      }
    };
    for (const Element<4>& e : tets) assemble(e);
    for (const Element<3>& e : faces) assemble(e);
    // Scaled so that the largest diagonal is 1.
    SparseMatrix k(static_cast<Eigen::Index>(count), static_cast<Eigen::Index>(count));
    k.setFromTriplets(entries.begin(), entries.end());
    entries = {};
    const double scale = 1.0 / k.diagonal().cwiseAbs().maxCoeff();
    k *= scale;
    rhs *= scale;
    Eigen::ConjugateGradient<SparseMatrix, Eigen::Lower | Eigen::Upper,
                             Eigen::IncompleteCholesky<double>>
        cg;
    cg.setTolerance(options.tolerance);
    cg.compute(k);
    if (cg.info() != Eigen::Success) {
      return absl::InternalError("flow: the preconditioner of the pressure system failed");
    }
    const Eigen::VectorXd p = cg.solve(rhs);
    *iterations = static_cast<int>(cg.iterations());
    *residual = std::max(*residual, cg.error());
    if (cg.info() != Eigen::Success) {
      return absl::InternalError(absl::StrCat("flow: the pressure along ", std::string(1, "xyz"[d]),
                                              " did not converge in ", cg.iterations(),
                                              " iterations (relative residual ", cg.error(), ")"));
    }
    for (size_t i = 0; i < n; ++i) {
      if (unknown[i] >= 0) pressure[static_cast<Eigen::Index>(i)] = p[unknown[i]];
    }
    return pressure;
  };
  // The mean flux of a solution, by kind of element.
  auto mean_flux = [&](const Eigen::VectorXd& pressure) {
    std::array<Vec3, 3> flux{};
    auto add = [&](const auto& e) {
      Vec3 g;
      for (size_t a = 0; a < e.nodes.size(); ++a) g += e.gradient[a] * pressure[e.nodes[a]];
      flux[e.kind] += g * (-e.conductivity * e.measure / out.volume);
    };
    for (const Element<4>& e : tets) add(e);
    for (const Element<3>& e : faces) add(e);
    return flux;
  };

  // The tensor: the pressure held linear on every face of the box.
  std::vector<Eigen::VectorXd> pressure;
  std::array<std::array<Vec3, 3>, 3> flux{};  // [axis][kind]
  for (int d = 0; d < 3; ++d) {
    SM_RETURN_IF_ERROR(
        progress.Update(0.5 * d / 3, absl::StrCat("solve ", std::string(1, "xyz"[d]))));
    SM_ASSIGN_OR_RETURN(Eigen::VectorXd p,
                        solve(0x3f, d, &out.residual, &out.iterations[d], &out.unknowns));
    flux[d] = mean_flux(p);
    pressure.push_back(std::move(p));
  }
  out.fixed_nodes = n - out.unknowns;
  // The permeameters: along d the pressure held on the two faces across d only.
  for (int d = 0; d < 3; ++d) {
    SM_RETURN_IF_ERROR(
        progress.Update(0.5 + 0.5 * d / 3, absl::StrCat("permeameter ", std::string(1, "xyz"[d]))));
    int iterations = 0;
    SM_ASSIGN_OR_RETURN(const Eigen::VectorXd p,
                        solve(uint8_t(3) << (2 * d), d, &out.residual, &iterations, nullptr));
    const std::array<Vec3, 3> f = mean_flux(p);
    out.permeameter[d] = (&f[0].x)[d] + (&f[1].x)[d] + (&f[2].x)[d];
  }
  if (fields != nullptr) {
    const size_t cells = mesh.tets.size() + mesh.faces.size();
    for (int d = 0; d < 3; ++d) {
      const std::string axis(1, "xyz"[d]);
      std::vector<double> p(pressure[d].data(), pressure[d].data() + n);
      fields->node_scalars.emplace_back("pressure_" + axis, std::move(p));
      std::vector<Vec3> v(cells);
      auto velocity = [&](const auto& e) {
        Vec3 g;
        for (size_t a = 0; a < e.nodes.size(); ++a) g += e.gradient[a] * pressure[d][e.nodes[a]];
        v[e.cell] = g * -e.velocity;
      };
      for (const Element<4>& e : tets) velocity(e);
      for (const Element<3>& e : faces) velocity(e);
      fields->cell_vectors.emplace_back("velocity_" + axis, std::move(v));
    }
  }
  for (int d = 0; d < 3; ++d) {
    const Vec3 total = flux[d][0] + flux[d][1] + flux[d][2];
    for (int i = 0; i < 3; ++i) out.tensor[i][d] = (&total.x)[i];
    const double along = (&total.x)[d];
    out.fracture_share[d] = along != 0 ? (&flux[d][1].x)[d] / along : 0;
    out.body_share[d] = along != 0 ? (&flux[d][2].x)[d] / along : 0;
  }
  Principal(out.tensor, &out.principal, &out.principal_directions);
  if (faces.empty()) {
    out.note =
        "no sheet face carries an aperture: the tensor is the rock's (and the bodies') alone";
  } else if (closed > 0) {
    out.note = absl::StrCat(closed, " sheet faces of aperture 0 (over holes) carry no flow");
  }
  out.seconds = absl::ToDoubleSeconds(absl::Now() - start);
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return out;
}

}  // namespace sheetmesh
