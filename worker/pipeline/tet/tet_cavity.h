// Cavities for vertex insertion into a tetrahedral mesh under improvement: the
// tetrahedra a new point replaces (those whose circumsphere holds it, grown or shrunk until
// every face of the cavity's boundary sees the point, never across a facet) and the fill
// that replaces them. Internal to the improvement.
#ifndef SHEETMESH_WORKER_PIPELINE_TET_TET_CAVITY_H_
#define SHEETMESH_WORKER_PIPELINE_TET_TET_CAVITY_H_

#include <cstdint>
#include <utility>
#include <vector>

#include "absl/container/flat_hash_set.h"
#include "worker/pipeline/tet/tet_mesh_editor.h"

namespace sheetmesh {

// The cavity of point p for the insertion near sliver t, and the tetrahedra that fill it
// (each boundary face with slot 3 left for the new vertex). False when p is not inside
// the domain on this side of the facets, or no valid cavity holds t.
bool Cavity(const TetMeshEditor& ed, uint32_t t, const Vec3& p, std::vector<uint32_t>* cavity,
            std::vector<Tet>* fill);

// The cavity of point p grown from the `seeds` (which it must keep: those p lies in or
// on) and its fill, as for Cavity. The facets in `opened` (those p lies on) are split by
// p: the cavity spans both their sides, and must keep their edges, given in `keep`, on
// its boundary (not all the tetrahedra around one inside).
bool GrowCavity(const TetMeshEditor& ed, const Vec3& p, const std::vector<uint32_t>& seeds,
                const absl::flat_hash_set<FaceKey>& opened,
                const std::vector<std::pair<uint32_t, uint32_t>>& keep,
                std::vector<uint32_t>* cavity, std::vector<Tet>* fill);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_TET_TET_CAVITY_H_
