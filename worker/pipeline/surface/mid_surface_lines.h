// The junction lines of the mid-surface's charts (mid_surface_junctions.h): which charts
// meet and by which voxels, and the straight lines where their planes near the contact
// cross, lines along one another merged and ending where they meet another line. Internal to
// the mid-surface.
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_LINES_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_LINES_H_

#include <cstdint>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "common/types.h"
#include "worker/pipeline/surface/mid_surface_chart.h"
#include "worker/pipeline/surface/mid_surface_junction_line.h"

namespace sheetmesh {

// A voxel's index in a box of `dims`, and its six neighbours' steps.
inline uint64_t VoxelKey(const Index3& p, const Dims& dims) {
  return static_cast<uint64_t>(p.x) +
         static_cast<uint64_t>(dims.nx) *
             (static_cast<uint64_t>(p.y) + static_cast<uint64_t>(dims.ny) * p.z);
}
inline constexpr int kStep[6][3] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},
                                    {0, -1, 0}, {0, 0, 1},  {0, 0, -1}};

// How far from their junction two sheets of `thickness` meeting at an angle of this sine
// run together (their runs merge): the planes near a contact are fitted beyond it, and
// what a cut leaves beyond a line within it is the junction's.
double MergeWidth(double thickness, double sine);

// Where two charts meet: the voxels by which they do (an even subsample past
// kMaxContactPoints).
inline constexpr size_t kMaxContactPoints = 4000;  // a line's fit needs no more
struct Contact {
  std::vector<Vec3> points;
  uint64_t count = 0;
  void Add(const Vec3& p);
};

// Which charts meet, and by which voxels: those that touch, and those that touch one
// component of the `loose` voxels (in no chart).
std::map<std::pair<int32_t, int32_t>, Contact> FindContacts(
    const std::vector<std::unique_ptr<Chart>>& charts, const std::vector<Index3>& loose,
    const Dims& dims);

// The junction lines of `contacts`: per contact the line where the two charts' planes near it
// cross, lines along one another merged; with each line the planes and thickness of its
// charts.
struct LineSet {
  std::vector<JunctionLine> lines;
  std::vector<std::vector<std::pair<int32_t, std::pair<Vec3, Vec3>>>> planes;  // per line
  std::vector<std::vector<double>> thickness;
};

LineSet MakeLines(const std::vector<std::unique_ptr<Chart>>& charts,
                  const std::map<std::pair<int32_t, int32_t>, Contact>& contacts, const Dims& dims,
                  const JunctionOptions& options);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_MID_SURFACE_LINES_H_
