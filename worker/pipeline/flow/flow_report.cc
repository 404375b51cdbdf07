// The report's part of the flow layer: the `Fields()` of its results.
#include <nlohmann/json.hpp>

#include "worker/pipeline/flow/image_permeability.h"
#include "worker/pipeline/flow/permeability.h"

namespace sheetmesh {

nlohmann::json PermeabilityResult::Fields() const {
  auto darcy = [](const Tensor3& t) {
    Tensor3 d = t;
    for (auto& row : d) {
      for (double& v : row) v /= kSquareMetresPerDarcy;
    }
    return d;
  };
  nlohmann::json directions = nlohmann::json::array();
  for (const Vec3& v : principal_directions) directions.push_back({v.x, v.y, v.z});
  std::array<double, 3> principal_darcy{};
  for (int k = 0; k < 3; ++k) principal_darcy[k] = principal[k] / kSquareMetresPerDarcy;
  nlohmann::json j = {
      {"permeability_m2", tensor},
      {"permeability_darcy", darcy(tensor)},
      {"principal_m2", principal},
      {"principal_darcy", principal_darcy},
      {"principal_directions", directions},
      {"permeameter_m2", permeameter},
      {"permeameter_darcy",
       {permeameter[0] / kSquareMetresPerDarcy, permeameter[1] / kSquareMetresPerDarcy,
        permeameter[2] / kSquareMetresPerDarcy}},
      {"fracture_share_of_flux", fracture_share},
      {"body_share_of_flux", body_share},
      {"boundary_conditions",
       "tensor: for each axis d, the pressure -x_d (a unit gradient along d) on every node "
       "of the box's faces, column d the mean flux over the box; permeameter: the pressure "
       "-x_d on the two faces across d only, no flow through the others"},
      {"solver", "conjugate gradients, incomplete Cholesky preconditioner (Eigen)"},
      {"iterations", iterations},
      {"relative_residual", residual},
      {"unknowns", unknowns},
      {"fixed_nodes", fixed_nodes},
      {"sheet_faces", sheet_faces},
      {"body_tets", body_tets},
      {"box_volume_m3", volume},
      {"metres_per_unit", metres_per_unit},
      {"seconds", seconds}};
  if (!body_permeability.empty()) {
    nlohmann::json bodies = nlohmann::json::object();
    for (const auto& [piece, k] : body_permeability) bodies[std::to_string(piece)] = k;
    j["body_permeability_m2"] = bodies;
  }
  if (!note.empty()) j["note"] = note;
  return j;
}

nlohmann::json ImagePermeability::Fields() const {
  nlohmann::json directions = nlohmann::json::array();
  for (const Vec3& v : principal_directions) directions.push_back({v.x, v.y, v.z});
  return {{"method",
           "finite volumes on the voxel grid: each sheet voxel (tau h)^2/12, the rock "
           "permeability.matrix; along each axis a permeameter (the pressure -x_d on the two "
           "faces across it, no flow through the others)"},
          {"permeability_m2", tensor},
          {"principal_m2", principal},
          {"principal_directions", directions},
          {"mesh_to_image_per_axis", mesh_to_image},
          {"iterations", iterations},
          {"relative_residual", residual},
          {"cells", cells},
          {"seconds", seconds}};
}

}  // namespace sheetmesh
