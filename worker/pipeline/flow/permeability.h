// The sample's effective permeability tensor from its volume mesh (beyond the paper): a
// conforming discrete-fracture model. Darcy flow in the rock by linear finite elements on
// the tetrahedra (the matrix permeability k_m), each sheet triangle a 2-D element on the same
// nodes whose transmissivity is the local cubic law a³/12 of its aperture a, and each body
// a region of its own permeability. Three solves, each with the pressure p = −x_d (a unit
// gradient along axis d) held on every node of the box's faces, give the tensor's columns
// from the mean fluxes: K e_d = (1/V) (Σ_tets V k ∇(−p) + Σ_sheet faces A (a³/12) ∇ₛ(−p)).
// With the pressure linear on the whole boundary the mean gradient is exactly the one
// imposed, so the tensor is the upper (Voigt-like) estimate of the sample's; a homogeneous
// sample is reproduced exactly.
#ifndef SHEETMESH_WORKER_PIPELINE_FLOW_PERMEABILITY_H_
#define SHEETMESH_WORKER_PIPELINE_FLOW_PERMEABILITY_H_

#include <array>
#include <cstdint>
#include <map>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "absl/status/statusor.h"
#include "common/length_unit.h"
#include "common/progress.h"
#include "common/types.h"
#include "worker/pipeline/tet/tet_mesh.h"
#include "worker/pipeline/tet/volume_mesh_io.h"

namespace sheetmesh {

inline constexpr double kSquareMetresPerDarcy = 9.869233e-13;

struct FlowOptions {
  bool enabled = false;
  double matrix_permeability = 1e-18;  // m², the rock between the sheets (about a microdarcy)
  // m², inside the pieces meshed as bodies; 0: each body's own, the parallel-plate law a²/12
  // of its thickness a = 2 × its volume / its wall area (what the body would carry as a
  // sheet of that aperture: a thick fracture meshed as a body keeps its cubic law)
  double body_permeability = 0;
  double tolerance = 1e-10;     // the conjugate gradients' relative residual
  bool image_reference = true;  // also the image's own answer (up to a million voxels)
};

using Tensor3 = std::array<std::array<double, 3>, 3>;

struct PermeabilityResult {
  double metres_per_unit = 1;  // what one length unit of the mesh is in metres
  Tensor3 tensor{};            // k_ij, m²: column j the mean flux of a unit gradient along j
  std::array<double, 3> principal{};         // eigenvalues, largest first
  std::array<Vec3, 3> principal_directions;  // unit vectors, in that order
  // Per axis, a permeameter's: the pressure −x_d on the two faces across d, no flow through
  // the other four (the laboratory's measurement; below the tensor's diagonal where the
  // sheets reach the side faces but do not cross from inlet to outlet).
  std::array<double, 3> permeameter{};
  std::array<double, 3> fracture_share{};  // per axis: the sheets' part of the mean flux
  std::array<double, 3> body_share{};      // and the bodies'
  std::array<int, 3> iterations{};
  double residual = 0;  // the largest relative residual of the three solves
  uint64_t unknowns = 0;
  uint64_t fixed_nodes = 0;                     // on the box's faces
  uint64_t sheet_faces = 0;                     // 2-D elements
  uint64_t body_tets = 0;                       // tetrahedra in bodies
  std::map<int32_t, double> body_permeability;  // m², per body piece, as used
  double volume = 0;                            // of the box, m³
  double seconds = 0;
  std::string note;  // what the result does not show ("" when nothing)

  nlohmann::json Fields() const;
};

// The principal values of `t`'s symmetric part, largest first, and their unit directions.
void Principal(const Tensor3& t, std::array<double, 3>* values, std::array<Vec3, 3>* directions);

// kInvalidArgument naming `field` and `k` unless 0 < k <= 1e-3 m².
absl::Status CheckPermeability(double k, const char* field);

// Solves the three problems on `mesh` and returns the tensor. kInvalidArgument for a
// permeability that is not positive and finite or beyond 1e-3 m² (field and value named),
// a sheet face of negative or non-finite aperture (naming it), a mesh without tetrahedra,
// or one whose length unit is not known (a permeability needs metres); kInternal when the solver
// does not converge (naming the axis and residual); kCancelled if asked. `fields`, when
// given, receives the three solutions for volume.vtu: per node pressure_x, pressure_y,
// pressure_z (the pressure under a unit gradient along that axis, −x_d on the box) and per
// cell velocity_x, velocity_y, velocity_z, the Darcy velocity times the viscosity under that
// gradient (m²: −k ∇p in the rock and bodies, −(a²/12) ∇p along a sheet face, 0 on the box's
// faces and bodies' walls).
absl::StatusOr<PermeabilityResult> SolvePermeability(const TetMesh& mesh,
                                                     const FlowOptions& options,
                                                     const Progress& progress = {},
                                                     VolumeFields* fields = nullptr);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_FLOW_PERMEABILITY_H_
