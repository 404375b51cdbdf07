#include "worker/pipeline/scvd/dual_triangles.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>

#include "common/status_macros.h"
#include "worker/pipeline/scvd/dual_triangles_parts.h"

namespace sheetmesh {

absl::StatusOr<DualTriangulation> TriangulateScvd(const VoxelSet& set,
                                                  const NeighborTable& neighbors,
                                                  std::span<const uint16_t> thickness,
                                                  const Scvd& scvd, std::span<const Vec3> positions,
                                                  const DualTriangleOptions& options,
                                                  const Progress& progress) {
  DualTriangulation result;
  if (positions.size() != scvd.num_generators()) {
    return absl::InvalidArgumentError("one vertex position per generator is required");
  }
  absl::flat_hash_set<uint64_t> adjacency;
  adjacency.reserve(scvd.adjacency.size());
  for (const auto& [a, b] : scvd.adjacency) adjacency.insert(PairKey(a, b));

  const Dims& d = set.dims();
  const size_t plane = static_cast<size_t>((d.nx + 2) * (d.ny + 2));
  tbb::combinable<BlockScan> scans;
  tbb::parallel_for(tbb::blocked_range<int64_t>(-1, d.nz),
                    [&](const tbb::blocked_range<int64_t>& r) {
                      std::vector<uint32_t> lo(plane, kNoCell), hi(plane, kNoCell);
                      BlockScan& out = scans.local();
                      for (int64_t z = r.begin(); z < r.end(); ++z) {
                        ScanSlicePair(set, scvd, z, &lo, &hi, adjacency, positions, &out);
                      }
                    });
  std::vector<Candidate> all;
  scans.combine_each([&](BlockScan& s) {
    result.stats.blocks_three += s.three;
    result.stats.blocks_amended += s.amended;
    result.stats.blocks_unresolved += s.unresolved;
    all.insert(all.end(), s.candidates.begin(), s.candidates.end());
    s.candidates = {};
  });
  SM_RETURN_IF_ERROR(progress.Update(0.4));
  tbb::parallel_sort(all.begin(), all.end());

  // One candidate per generator triple, with its votes; a triple that any plain block gave
  // counts as plain.
  struct Ranked {
    Candidate c;
    uint32_t votes;
    double min_angle;
  };
  std::vector<Ranked> ranked;
  for (size_t i = 0; i < all.size();) {
    size_t j = i;
    uint32_t plain = 0;
    while (j < all.size() && all[j].SameFace(all[i])) {
      plain += all[j].amended == 0;
      ++j;
    }
    Candidate c = all[i];
    c.amended = plain > 0 ? 0 : 1;
    const Triangle t = {positions[c.a], positions[c.b], positions[c.c]};
    ranked.push_back({c, static_cast<uint32_t>(j - i), MinAngleDegrees(t)});
    i = j;
  }
  all = {};
  result.stats.candidates = ranked.size();
  std::sort(ranked.begin(), ranked.end(), [](const Ranked& x, const Ranked& y) {
    if (x.votes != y.votes) return x.votes > y.votes;
    if (x.c.amended != y.c.amended) return x.c.amended < y.c.amended;
    if (x.min_angle != y.min_angle) return x.min_angle > y.min_angle;
    return x.c < y.c;
  });

  // Greedy selection, most-voted first.
  double edge_sum = 0;
  for (const Ranked& r : ranked) edge_sum += Norm(positions[r.c.a] - positions[r.c.b]);
  const double cell = std::max(1.0, 2.0 * edge_sum / std::max<size_t>(1, ranked.size()));
  std::vector<Vec3> pos(positions.begin(), positions.end());
  FaceSelector selector(&pos, cell, options);
  for (size_t i = 0; i < ranked.size(); ++i) {
    if ((i & 0xFFFF) == 0) SM_RETURN_IF_ERROR(progress.Update(0.4 + 0.5 * i / ranked.size()));
    const Candidate& c = ranked[i].c;
    const FaceSelector::Verdict v = selector.TryAdd({c.a, c.b, c.c});
    Count(v, &result.stats);
    if (v == FaceSelector::Verdict::kKept) result.votes.push_back(ranked[i].votes);
  }
  if (options.close_cracks) CloseCracks(set, options, pos, &selector, &result);
  if (options.rim) AddRim(set, neighbors, thickness, scvd, options, &pos, &selector, &result);
  result.faces = selector.faces();
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return result;
}

}  // namespace sheetmesh
