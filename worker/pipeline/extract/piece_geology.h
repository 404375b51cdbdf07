// Per-piece geology, beyond the paper: for every extracted piece its size, mesh area,
// aperture, best-fit plane with dip and dip direction, and centroid — what geologists
// plot first (rose diagrams, stereonets, aperture distributions).
#ifndef SHEETMESH_WORKER_PIPELINE_EXTRACT_PIECE_GEOLOGY_H_
#define SHEETMESH_WORKER_PIPELINE_EXTRACT_PIECE_GEOLOGY_H_

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <span>
#include <string>
#include <vector>

#include "common/types.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/voxel/labelled_voxels.h"

namespace sheetmesh {

struct PieceGeology {
  int32_t piece = 0;
  int32_t sheet = 0;  // pieces in one plane (B and C of Fig. 4, split by a crossing) share it
  uint64_t voxels = 0;
  uint64_t triangles = 0;    // faces of the mesh carrying this piece
  double area = 0;           // mesh area of those faces, physical units^2
  double mean_aperture = 0;  // mean τ along the plane normal, physical units
  double max_aperture = 0;
  Vec3 normal;  // best-fit plane (least squares), unit, z >= 0
  double dip_degrees = 0;
  double dip_direction_degrees = 0;
  double planarity = 0;  // 1 - λ_min / λ_mid of the voxels' covariance
  Vec3 centroid;         // physical units

  // The row of the pieces table, for the report.
  nlohmann::json Fields() const;
};

// The geology of every label of `model`. `thickness` is τ per voxel of model.set; faces of
// `mesh` (voxel coordinates, face_piece set) give triangles and area. Pieces ordered by
// label.
std::vector<PieceGeology> ComputePieceGeology(const LabelledVoxels& model,
                                              std::span<const uint16_t> thickness,
                                              const TriangleMesh& mesh, const Placement& placement);

// Pieces in one plane are one sheet: normals within this angle, each centroid within half
// their two max apertures of the other's plane, one of them at least this planar.
inline constexpr double kSheetAngleDegrees = 10.0;
inline constexpr double kSheetMinPlanarity = 0.8;

// Sets every piece's sheet id (0, 1, ... in the order of each sheet's first piece).
void AssignSheets(std::vector<PieceGeology>* pieces);

// Each piece's mean (area-weighted) and largest aperture from its faces' aperture
// (mesh.face_aperture_voxels, made physical by `placement`), where it has faces: the
// apertures measured on the mesh, from the grey levels, rather than counted from voxels.
void UseFaceApertures(const TriangleMesh& mesh, const Placement& placement,
                      std::vector<PieceGeology>* pieces);

// CSV with a header line: piece, voxels, triangles, area, mean_aperture, max_aperture,
// normal_x/y/z, dip, dip_direction, planarity, centroid_x/y/z, sheet.
std::string PieceGeologyCsv(const std::vector<PieceGeology>& pieces);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_EXTRACT_PIECE_GEOLOGY_H_
