// Tetrahedron quality (paper Table 3; ALGORITHM §11): minimum dihedral angle, gamma (Lo
// 1997), edge aspect and radius aspect, each with min, mean and a histogram.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_TET_QUALITY_H_
#define SHEETMESH_WORKER_PIPELINE_TET_TET_QUALITY_H_

#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "worker/pipeline/tet/tet_mesh.h"

namespace sheetmesh {

// The smallest dihedral angle of the tetrahedron (a, b, c, d) in degrees, or a negative
// number when it is inverted or flat (TetVolume <= 0).
double MinDihedralDegrees(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// The four measures of one tetrahedron. A regular tetrahedron has 70.53°, 1, 1, 1.
struct TetShape {
  double min_dihedral_degrees = 0;
  double gamma = 0;          // 72 √3 V / (Σ l_i²)^{3/2}
  double edge_aspect = 0;    // l_min / l_max
  double radius_aspect = 0;  // 3 r_in / R_circ
};
TetShape MeasureTet(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// 3 r_in / R_circ of the tetrahedron (1 when regular, 0 when flat).
double RadiusAspect(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);
// The same from its (unsigned) volume and total face area, when those are at hand.
double RadiusAspect(double volume, double area, const Vec3& a, const Vec3& b, const Vec3& c,
                    const Vec3& d);

struct QualityStat {
  std::string name;
  double min = 0;
  double mean = 0;
  double lo = 0, hi = 1;            // histogram range
  std::vector<uint64_t> histogram;  // equal bins over [lo, hi]

  // min, mean, histogram_range, histogram.
  nlohmann::json Fields() const;
};

struct TetQuality {
  QualityStat min_dihedral;  // degrees, bins of 5° over [0, 90]
  QualityStat gamma;         // bins of 0.05 over [0, 1]
  QualityStat edge_aspect;
  QualityStat radius_aspect;
  uint64_t tets = 0;
  uint64_t nodes = 0;
  double volume = 0;      // sum of tetrahedron volumes
  uint64_t inverted = 0;  // tetrahedra of non-positive volume

  // The four measures by name (Table 3's rows), for the report.
  nlohmann::json Fields() const;
};

TetQuality MeasureQuality(const TetMesh& mesh);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_TET_QUALITY_H_
