// VDB structure check: walks a .vdb file as OpenVDB 10 will read it — header, metadata, grid
// descriptors, then one grid's metadata, transform, tree topology and leaf buffers — and
// checks every count, size and offset against the file and a memory budget before OpenVDB
// sees the file. OpenVDB trusts what it reads: a chunk size it does not compare with the
// chunk it fills wrote past a buffer, and a node count it believed allocated gigabytes. No
// OpenVDB header is included here (OpenVDB stays in the .cc files).
#ifndef SHEETMESH_WORKER_PIPELINE_VOLUME_VDB_CHECK_H_
#define SHEETMESH_WORKER_PIPELINE_VOLUME_VDB_CHECK_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace sheetmesh {

// One grid descriptor of a .vdb file.
struct VdbGridEntry {
  std::string name;             // the unique name OpenVDB reads it by
  std::string type;             // "Tree_float_5_4_3" (without "_HalfFloat")
  bool half = false;            // float values saved as 16-bit halves
  std::string instance_parent;  // the grid whose tree this one shares ("" = its own)
  int64_t grid_pos = 0, block_pos = 0, end_pos = 0;
};

// The file's header and descriptors.
struct VdbFileLayout {
  uint32_t version = 0;  // the file format version
  std::vector<VdbGridEntry> grids;
};

// Reads the header, the file's metadata and the grid descriptors of `path`, every length and
// offset within the file. kInvalidArgument naming the file, the byte and what is wrong (not
// OpenVDB's magic, a format version other than OpenVDB 3 to 10's (222-224), a count or
// length past the end, a grid placed outside the file); the error of the file system
// otherwise.
absl::StatusOr<VdbFileLayout> ReadVdbLayout(const std::string& path);

// Whether grids of `type` are scalar grids the reader takes: float, double, int32, int64,
// bool and mask trees of the standard 5-4-3 configuration.
bool IsScalarVdbGridType(const std::string& type);

// Walks grid `index` of `layout` (and, for an instance, its parent's tree) as OpenVDB reads
// it: compression flags, metadata (each registered type at its size, a delayed-load table
// checked whole), transform (the linear maps), the root's tiles and children (aligned,
// unique), every internal node's masks and values, every leaf's mask and buffer (the same
// mask in topology and buffers, a bool or mask leaf's origin where the tree puts it), and
// every compressed chunk (an uncompressed chunk exactly the size it fills, a blosc chunk
// whose header declares that size and its own length, a zip chunk within the file).
// kInvalidArgument naming the file, byte and field at the first disagreement;
// kResourceExhausted when the tree OpenVDB would build takes more than `memory_budget`
// bytes. Reads the file once, in order; memory: 16 bytes a leaf.
absl::Status CheckVdbGrid(const std::string& path, const VdbFileLayout& layout, size_t index,
                          int64_t memory_budget);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_VOLUME_VDB_CHECK_H_
