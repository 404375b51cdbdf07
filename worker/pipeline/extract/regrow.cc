#include "worker/pipeline/extract/regrow.h"

#include <algorithm>
#include <cmath>

#include "absl/container/flat_hash_map.h"
#include "absl/strings/str_cat.h"
#include "common/status_macros.h"
#include "worker/pipeline/extract/scvd_of_set.h"
#include "worker/pipeline/mesh/vertex_normals.h"

namespace sheetmesh {
namespace {

struct Plane {
  Vec3 point;
  Vec3 normal;  // zero: the cell had no triangle, it does not grow
  float half_thickness = 0;
  int32_t label = 0;
};

constexpr uint32_t kUnclaimed = UINT32_MAX;

// The cells of the patch's own SCVD.
absl::StatusOr<CellPlanes> BuildCellPlanes(const VoxelSet& set, const ExtendOptions& o,
                                           const Progress& progress) {
  SM_ASSIGN_OR_RETURN(ScvdOfSet s, BuildScvdOfSet(set, o.scvd_radius_voxels, o.seed, progress));
  CellPlanes c;
  c.thickest.assign(s.scvd.num_generators(), 0);
  for (size_t v = 0; v < s.scvd.cell.size(); ++v) {
    const uint32_t g = s.scvd.cell[v];
    if (g < c.thickest.size()) c.thickest[g] = std::max(c.thickest[g], s.sheet.thickness[v]);
  }
  c.normal = VertexNormals(s.positions, s.faces);
  c.centroid = std::move(s.scvd.centroid);
  c.cell_of_voxel = std::move(s.scvd.cell);
  return c;
}

// One plane per cell, labelled like the patch's voxels in it.
std::vector<Plane> PlanesOf(const LabelledVoxels& patch, const CellPlanes& c, double t) {
  std::vector<Plane> planes(c.centroid.size());
  for (uint32_t g = 0; g < planes.size(); ++g) {
    planes[g].point = c.centroid[g];
    planes[g].normal = c.normal[g];
    planes[g].half_thickness = static_cast<float>(std::max(t, 0.5 * c.thickest[g] + 0.5));
  }
  for (size_t i = 0; i < patch.label.size(); ++i) {
    const uint32_t g = c.cell_of_voxel[i];
    if (g < planes.size()) planes[g].label = patch.label[i];
  }
  return planes;
}

}  // namespace

absl::StatusOr<ExtendResult> Regrow(const LabelledVoxels& patch, const ExtendOptions& o,
                                    const VoxelSet& within, const CellPlanes* known,
                                    const Progress& progress) {
  if (!(o.half_thickness_voxels > 0) || !(o.scvd_radius_voxels > 0)) {
    return absl::InvalidArgumentError(absl::StrCat("recover t = ", o.half_thickness_voxels,
                                                   " and r = ", o.scvd_radius_voxels,
                                                   " must both be positive"));
  }
  if (!(within.dims() == patch.set.dims())) {
    return absl::InvalidArgumentError("recover: the image's dims differ from the patch's");
  }
  ExtendResult out;
  out.patch = patch;
  const VoxelSet open = Difference(within, patch.set);  // what may be claimed
  if (patch.set.empty() || open.empty()) return out;
  CellPlanes own;
  if (known == nullptr) {
    SM_ASSIGN_OR_RETURN(own, BuildCellPlanes(patch.set, o, progress.Sub(0, 0.8)));
    known = &own;
  } else if (known->cell_of_voxel.size() != patch.set.size()) {
    return absl::InternalError("recover: the cells given do not cover the patch");
  }
  const std::vector<Plane> planes = PlanesOf(patch, *known, o.half_thickness_voxels);
  const std::vector<uint32_t>& cell = known->cell_of_voxel;
  const Dims& d = patch.set.dims();
  auto key = [&](int64_t x, int64_t y, int64_t z) {
    return static_cast<uint64_t>((z * d.ny + y) * d.nx + x);
  };
  // The plane of every open voxel once claimed.
  absl::flat_hash_map<uint64_t, uint32_t> plane_of;
  plane_of.reserve(open.size());
  open.ForEachVoxel(
      [&](uint64_t, int32_t x, int32_t y, int32_t z) { plane_of[key(x, y, z)] = kUnclaimed; });
  // The plane a labelled voxel carries (kUnclaimed: not labelled).
  auto carried = [&](int64_t x, int64_t y, int64_t z) -> uint32_t {
    const int64_t i = patch.set.Find(x, y, z);
    if (i >= 0) return cell[i];
    auto it = plane_of.find(key(x, y, z));
    return it == plane_of.end() ? kUnclaimed : it->second;
  };
  std::vector<Index3> front;  // open voxels to look at this round
  open.ForEachVoxel([&](uint64_t, int32_t x, int32_t y, int32_t z) { front.push_back({x, y, z}); });
  std::vector<std::pair<uint64_t, uint32_t>> claims;
  while (!front.empty() && (o.max_rounds == 0 || out.rounds < o.max_rounds)) {
    claims.clear();
    for (const Index3& p : front) {
      if (plane_of[key(p.x, p.y, p.z)] != kUnclaimed) continue;
      uint32_t best = kUnclaimed;
      double best_off = 0;
      for (int dz = -1; dz <= 1; ++dz) {
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int64_t x = p.x + dx, y = p.y + dy, z = p.z + dz;
            if ((dx | dy | dz) == 0 || !d.Contains(x, y, z)) continue;
            const uint32_t c = carried(x, y, z);
            if (c == kUnclaimed || Norm2(planes[c].normal) == 0) continue;
            const double off =
                std::abs(Dot(Vec3(p.x, p.y, p.z) - planes[c].point, planes[c].normal));
            if (off >= planes[c].half_thickness) continue;
            if (best == kUnclaimed || off < best_off || (off == best_off && c < best)) {
              best = c;
              best_off = off;
            }
          }
        }
      }
      if (best != kUnclaimed) claims.emplace_back(key(p.x, p.y, p.z), best);
    }
    if (claims.empty()) break;
    // Claims take effect together, so the order of the front does not matter.
    for (const auto& [k, c] : claims) plane_of[k] = c;
    out.added += claims.size();
    ++out.rounds;
    front.clear();
    for (const auto& [k, c] : claims) {
      const int64_t x = static_cast<int64_t>(k % d.nx), row = static_cast<int64_t>(k / d.nx);
      const int64_t y = row % d.ny, z = row / d.ny;
      for (int dz = -1; dz <= 1; ++dz) {
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            auto it = plane_of.find(key(x + dx, y + dy, z + dz));
            if (d.Contains(x + dx, y + dy, z + dz) && it != plane_of.end() &&
                it->second == kUnclaimed) {
              front.push_back({static_cast<int32_t>(x + dx), static_cast<int32_t>(y + dy),
                               static_cast<int32_t>(z + dz)});
            }
          }
        }
      }
    }
    std::sort(front.begin(), front.end(), [](const Index3& a, const Index3& b) {
      return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
    });
    front.erase(std::unique(front.begin(), front.end(),
                            [](const Index3& a, const Index3& b) {
                              return a.x == b.x && a.y == b.y && a.z == b.z;
                            }),
                front.end());
    SM_RETURN_IF_ERROR(progress.Update(0.8 + 0.2 * (1 - 1.0 / (1 + out.rounds))));
  }
  // The patch with the claimed voxels, in linear order.
  std::vector<std::pair<uint64_t, int32_t>> merged;
  merged.reserve(patch.set.size() + out.added);
  patch.set.ForEachVoxel([&](uint64_t i, int32_t x, int32_t y, int32_t z) {
    merged.emplace_back(key(x, y, z), patch.label[i]);
  });
  for (const auto& [k, c] : plane_of) {
    if (c != kUnclaimed) merged.emplace_back(k, planes[c].label);
  }
  std::sort(merged.begin(), merged.end());
  VoxelSet::Builder b(d);
  LabelledVoxels grown;
  grown.label.reserve(merged.size());
  for (const auto& [k, label] : merged) {
    const int64_t row = static_cast<int64_t>(k / d.nx);
    b.AddVoxel(static_cast<int64_t>(k % d.nx), row % d.ny, row / d.ny);
    grown.label.push_back(label);
  }
  grown.set = std::move(b).Build();
  out.patch = std::move(grown);
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return out;
}

}  // namespace sheetmesh
