// The voxels a sheet face's prism holds, and how many prisms hold each voxel: what the
// fits of face heights (wall_fit.h) and vertex positions (vertex_fit.h) count formula 5 with.
#ifndef SHEETMESH_WORKER_PIPELINE_SURFACE_PRISM_COLUMNS_H_
#define SHEETMESH_WORKER_PIPELINE_SURFACE_PRISM_COLUMNS_H_

#include <cstdint>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "worker/pipeline/mesh/triangle_mesh.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// A voxel of a face's column: its distance to the face's plane, and the voxel (its index in
// the set, or its linear index, marked by `in_set`).
struct ColumnVoxel {
  double distance;
  uint64_t id;
  bool in_set;
  bool operator<(const ColumnVoxel& o) const { return distance < o.distance; }
};

// The voxels whose centres project into face f's triangle within `pad` of its plane, by
// distance (the prism of ALGORITHM §9 with height 2 pad).
void ColumnOf(const TriangleMesh& mesh, size_t f, const VoxelSet& set, double pad,
              std::vector<ColumnVoxel>* column);

// How many prisms hold each voxel: the set's by index, the others by linear index.
class Coverage {
 public:
  explicit Coverage(const VoxelSet& set) : in_(set.size(), 0) {}
  uint32_t Count(const ColumnVoxel& c) const {
    if (c.in_set) return in_[c.id];
    auto it = out_.find(c.id);
    return it == out_.end() ? 0 : it->second;
  }
  void Add(const ColumnVoxel& c, int delta) {
    if (c.in_set) {
      in_[c.id] = static_cast<uint32_t>(int64_t(in_[c.id]) + delta);
    } else {
      uint32_t& n = out_[c.id];
      n = static_cast<uint32_t>(int64_t(n) + delta);
    }
  }

 private:
  std::vector<uint32_t> in_;
  absl::flat_hash_map<uint64_t, uint32_t> out_;
};

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SURFACE_PRISM_COLUMNS_H_
