// ColumnGraph: a sheet seen as columns across its thickness. Every voxel belongs to the
// run of sheet voxels through it along its thinnest axis (the axis of τ); that run is a
// column, a node of the graph, placed at the run's middle voxel; two columns are linked
// when any of their voxels touch across a face. Growing cells over columns instead of
// voxels gives every column to one cell, so cells cannot stack across the thickness when
// r is close to it (ALGORITHM §4, the medial-surface choice). Runs longer than a cap are
// not thickness but extent (along a crossing): their voxels stay columns of one.
#ifndef SHEETMESH_WORKER_PIPELINE_SCVD_COLUMN_GRAPH_H_
#define SHEETMESH_WORKER_PIPELINE_SCVD_COLUMN_GRAPH_H_

#include <cstdint>
#include <span>
#include <vector>

#include "absl/status/statusor.h"
#include "worker/pipeline/voxel/neighbor_table.h"
#include "worker/pipeline/voxel/voxel_set.h"

namespace sheetmesh {

// A graph in compressed rows: the neighbours of node n are targets[offsets[n] ..
// offsets[n+1]).
struct CsrGraph {
  std::vector<uint64_t> offsets;
  std::vector<uint32_t> targets;

  uint32_t num_nodes() const {
    return offsets.empty() ? 0 : static_cast<uint32_t>(offsets.size() - 1);
  }
  std::span<const uint32_t> of(uint32_t n) const {
    return {targets.data() + offsets[n], targets.data() + offsets[n + 1]};
  }
};

struct ColumnGraph {
  std::vector<uint32_t> node_of_voxel;  // per voxel of the set
  std::vector<uint32_t> node_voxel;     // per node: the voxel it sits at (the run's middle)
  CsrGraph graph;

  uint32_t num_nodes() const { return static_cast<uint32_t>(node_voxel.size()); }
};

// Builds the columns of `set`. Runs along a voxel's thinnest axis (ties: z, then y, then x)
// of at most `max_column_voxels` voxels become columns; with `vote_block` > 1 the axis is
// the majority of the thinnest axes in the voxel's block of vote_block^3 (about a thickness
// wide), so runs cut short along the sheet near a rim do not cross the columns.
// The blocks lie on a grid whose lines pass through multiples of vote_block in the whole
// volume's coordinates, `origin` being the global position of the set's voxel (0, 0, 0), so
// a brick's columns agree with the whole's away from its faces. kResourceExhausted beyond
// 2^32 nodes.
absl::StatusOr<ColumnGraph> BuildColumnGraph(const VoxelSet& set, const NeighborTable& neighbors,
                                             uint32_t max_column_voxels, uint32_t vote_block = 0,
                                             const Index3& origin = {});

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_SCVD_COLUMN_GRAPH_H_
