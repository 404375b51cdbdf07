#include "worker/pipeline/extract/extend.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/status_macros.h"
#include "worker/pipeline/extract/scvd_of_set.h"
#include "worker/pipeline/mesh/vertex_normals.h"
#include "worker/pipeline/scvd/rim_classifier.h"

namespace sheetmesh {
namespace {

struct Claim {
  uint64_t key;     // linear voxel index
  float off_plane;  // |v . n|
  int32_t label;
  bool operator<(const Claim& o) const {
    if (key != o.key) return key < o.key;
    if (off_plane != o.off_plane) return off_plane < o.off_plane;
    return label < o.label;
  }
};

// One round: the claims of every rim generator's cylinder.
// The SCVD it was built on is moved to *built when that is not null.
absl::StatusOr<std::vector<Claim>> Round(const LabelledVoxels& patch, const ExtendOptions& o,
                                         const VoxelSet* within, const Progress& progress,
                                         ScvdOfSet* built) {
  const Dims& d = patch.set.dims();
  SM_ASSIGN_OR_RETURN(
      ScvdOfSet s, BuildScvdOfSet(patch.set, o.scvd_radius_voxels, o.seed, progress.Sub(0, 0.6)));
  const SheetAnalysis& sheet = s.sheet;
  const Scvd& scvd = s.scvd;
  // Formula 4's n: the normalised mean of the generator's triangles' normals.
  const std::vector<Vec3> normal = VertexNormals(s.positions, s.faces);
  // Cells on the rim (the outer edge or a hole's): the only ones whose cylinder can reach
  // beyond the patch in its plane.
  std::vector<uint8_t> rim_cell(scvd.num_generators(), 0);
  const RimClassifier rim(sheet.set, 0.4);
  sheet.set.ForEachVoxel([&](uint64_t v, int32_t x, int32_t y, int32_t z) {
    const uint32_t c = scvd.cell[v];
    if (!rim_cell[c] && Norm2(normal[c]) > 0 && rim.IsRim(x, y, z, normal[c])) rim_cell[c] = 1;
  });
  std::vector<uint32_t> active;
  for (uint32_t g = 0; g < scvd.num_generators(); ++g) {
    if (rim_cell[g]) active.push_back(g);
  }
  const double t = o.half_thickness_voxels, R = o.radius_voxels;
  // Each cylinder is scanned within its own bounding box, clipped to the image: along axis
  // i it reaches R sqrt(1 - n_i^2) + t |n_i| from Z.
  struct Window {
    int64_t lo[3], hi[3];
    int64_t voxels() const {
      int64_t v = 1;
      for (int k = 0; k < 3; ++k) v *= std::max<int64_t>(0, hi[k] - lo[k] + 1);
      return v;
    }
  };
  const int64_t extent[3] = {d.nx, d.ny, d.nz};
  auto window_of = [&](uint32_t g) {
    const Index3 z = scvd.generators[g];
    const double n[3] = {normal[g].x, normal[g].y, normal[g].z};
    const int64_t c[3] = {z.x, z.y, z.z};
    Window w;
    for (int k = 0; k < 3; ++k) {
      const double a = std::min(1.0, std::abs(n[k]));
      const int64_t reach =
          static_cast<int64_t>(std::ceil(R * std::sqrt(std::max(0.0, 1 - a * a)) + t * a));
      w.lo[k] = std::max<int64_t>(0, c[k] - reach);
      w.hi[k] = std::min<int64_t>(extent[k] - 1, c[k] + reach);
    }
    return w;
  };
  // What the round will cost, before it runs: the voxels it looks at, and the claims it may
  // hold at once (each cylinder's, at most its window).
  double visits = 0, claims_bound = 0;
  // A flat cylinder holds at most its own volume, and no more than the image's widest plane
  // section (at most the root of the sum of its faces' squared areas) times its thickness.
  const double nx = d.nx, ny = d.ny, nz = d.nz;
  const double widest = std::sqrt(nx * nx * ny * ny + ny * ny * nz * nz + nz * nz * nx * nx);
  const double cylinder = std::min(M_PI * (R + 1) * (R + 1), widest) * (2 * t + 2);
  for (const uint32_t g : active) {
    const double w = static_cast<double>(window_of(g).voxels());
    visits += w;
    claims_bound += std::min(w, cylinder);
  }
  // Claims are kept as a list (sorted, the nearest plane's first) or, where the cylinders
  // cover much of the image, as the best claim per voxel of a dense array: the same result.
  // The list is gathered slab by slab along z (each window's bound spread over its slices),
  // a slab's raw claims at most about o.slab_claims: what it holds at once is one slab's
  // claims and their union, and the voxels claimed so far, counted as they come.
  std::vector<double> per_slice(static_cast<size_t>(d.nz), 0.0);
  for (const uint32_t g : active) {
    const Window w = window_of(g);
    const double share = std::min(static_cast<double>(w.voxels()), cylinder) /
                         static_cast<double>(std::max<int64_t>(1, w.hi[2] - w.lo[2] + 1));
    for (int64_t z = w.lo[2]; z <= w.hi[2]; ++z) per_slice[z] += share;
  }
  std::vector<std::pair<int64_t, int64_t>> slabs;  // [z0, z1)
  double largest_slab = 0;
  for (int64_t z0 = 0; z0 < d.nz;) {
    double bound = per_slice[z0];
    int64_t z1 = z0 + 1;
    while (z1 < d.nz && bound + per_slice[z1] <= static_cast<double>(o.slab_claims)) {
      bound += per_slice[z1++];
    }
    slabs.emplace_back(z0, z1);
    largest_slab = std::max(largest_slab, bound);
    z0 = z1;
  }
  const double list_bytes = 2 * sizeof(Claim) * largest_slab;  // a slab's parts and union
  const double dense_bytes = sizeof(uint64_t) * static_cast<double>(d.num_voxels());
  const bool dense = o.claims == ExtendOptions::ClaimStore::kAuto
                         ? dense_bytes < 2 * sizeof(Claim) * claims_bound
                         : o.claims == ExtendOptions::ClaimStore::kDense;
  const double claim_bytes = dense ? dense_bytes : list_bytes;
  const auto too_much = [&](double bytes) {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "extending %d rim cells with t = %g and R = %g voxels would look at %.3g voxels and "
        "hold %.3g GB of claims (limits: %.3g voxels, %.3g GB of memory); lower t and R "
        "(formula 4's flat cylinder) to about the sheets' thickness and a cell's radius",
        active.size(), t, R, visits, bytes / 1e9, o.max_visits, o.memory_bytes / 1e9));
  };
  if (claim_bytes > static_cast<double>(o.memory_bytes) || visits > o.max_visits) {
    return too_much(claim_bytes);
  }
  // Calls claim(key, off_plane, label) for every voxel each rim cylinder may add in the
  // slices [z0, z1).
  auto scan = [&](int64_t z0, int64_t z1, auto&& claim) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, active.size(), 16),
                      [&](const tbb::blocked_range<size_t>& r) {
                        for (size_t i = r.begin(); i < r.end(); ++i) {
                          const uint32_t g = active[i];
                          const Window w = window_of(g);
                          const int64_t from = std::max(w.lo[2], z0);
                          const int64_t to = std::min(w.hi[2], z1 - 1);
                          if (from > to) continue;
                          const Index3 z = scvd.generators[g];
                          const Vec3& n = normal[g];
                          const int32_t label = patch.label[scvd.generator_voxel[g]];
                          for (int64_t zz = from; zz <= to; ++zz) {
                            for (int64_t y = w.lo[1]; y <= w.hi[1]; ++y) {
                              for (int64_t x = w.lo[0]; x <= w.hi[0]; ++x) {
                                const Vec3 v(x - z.x, y - z.y, zz - z.z);
                                const double along = std::abs(Dot(v, n));
                                if (along >= t) continue;
                                if (Norm2(v) - along * along >= R * R) continue;
                                if (patch.set.Contains(x, y, zz)) continue;
                                if (within != nullptr && !within->Contains(x, y, zz)) continue;
                                claim(static_cast<uint64_t>((zz * d.ny + y) * d.nx + x),
                                      static_cast<float>(along), label);
                              }
                            }
                          }
                        }
                      });
  };
  std::vector<Claim> claims;
  if (dense) {
    // (off_plane, label) packed so that the smaller word is the nearer plane, then the lower
    // label: a non-negative float's bits order as the float, the label offset to unsigned.
    constexpr uint64_t kNone = ~uint64_t{0};
    std::vector<std::atomic<uint64_t>> best(static_cast<size_t>(d.num_voxels()));
    tbb::parallel_for(size_t{0}, best.size(),
                      [&](size_t i) { best[i].store(kNone, std::memory_order_relaxed); });
    scan(0, d.nz, [&](uint64_t key, float along, int32_t label) {
      uint32_t bits;
      std::memcpy(&bits, &along, 4);
      const uint64_t word =
          (uint64_t{bits} << 32) | (static_cast<uint32_t>(label) ^ uint32_t{0x80000000u});
      uint64_t seen = best[key].load(std::memory_order_relaxed);
      while (word < seen &&
             !best[key].compare_exchange_weak(seen, word, std::memory_order_relaxed)) {
      }
    });
    for (size_t key = 0; key < best.size(); ++key) {
      const uint64_t word = best[key].load(std::memory_order_relaxed);
      if (word == kNone) continue;
      float along;
      const uint32_t bits = static_cast<uint32_t>(word >> 32);
      std::memcpy(&along, &bits, 4);
      claims.push_back(
          {key, along, static_cast<int32_t>(static_cast<uint32_t>(word) ^ uint32_t{0x80000000u})});
    }
  } else {
    std::vector<Claim> slab;
    for (const auto& [z0, z1] : slabs) {
      tbb::combinable<std::vector<Claim>> parts;
      scan(z0, z1, [&](uint64_t key, float along, int32_t label) {
        parts.local().push_back({key, along, label});
      });
      slab.clear();
      parts.combine_each(
          [&](std::vector<Claim>& p) { slab.insert(slab.end(), p.begin(), p.end()); });
      tbb::parallel_sort(slab.begin(), slab.end());
      // The first claim of each voxel is the nearest plane's (ties: the lower label). Slabs
      // follow each other in z, so their voxels come in linear order.
      slab.erase(std::unique(slab.begin(), slab.end(),
                             [](const Claim& a, const Claim& b) { return a.key == b.key; }),
                 slab.end());
      claims.insert(claims.end(), slab.begin(), slab.end());
      if (static_cast<double>(claims.size() * sizeof(Claim)) + list_bytes >
          static_cast<double>(o.memory_bytes)) {
        return too_much(static_cast<double>(claims.size() * sizeof(Claim)) + list_bytes);
      }
    }
  }
  if (built != nullptr) *built = std::move(s);
  return claims;
}

// `patch` with the claimed voxels added.
LabelledVoxels Merge(const LabelledVoxels& patch, const std::vector<Claim>& claims) {
  const Dims& d = patch.set.dims();
  VoxelSet::Builder b(d);
  LabelledVoxels out;
  out.label.reserve(patch.label.size() + claims.size());
  // Walk the old voxels and the claims (both in linear order) together, straight into the
  // builder: nothing the size of the patch besides its labels.
  const auto add = [&](uint64_t key, int32_t label) {
    const int64_t x = static_cast<int64_t>(key % d.nx);
    const int64_t row = static_cast<int64_t>(key / d.nx);
    b.AddVoxel(x, row % d.ny, row / d.ny);
    out.label.push_back(label);
  };
  size_t c = 0;
  patch.set.ForEachVoxel([&](uint64_t i, int32_t x, int32_t y, int32_t z) {
    const uint64_t key = (static_cast<uint64_t>(z) * d.ny + y) * d.nx + x;
    for (; c < claims.size() && claims[c].key < key; ++c) add(claims[c].key, claims[c].label);
    add(key, patch.label[i]);
  });
  for (; c < claims.size(); ++c) add(claims[c].key, claims[c].label);
  out.set = std::move(b).Build();
  return out;
}

}  // namespace

absl::StatusOr<ExtendResult> Extend(const LabelledVoxels& patch, const ExtendOptions& options,
                                    const VoxelSet* within, const Progress& progress,
                                    ScvdOfSet* first_round) {
  if (!(options.half_thickness_voxels > 0) || !(options.radius_voxels > 0) ||
      !(options.scvd_radius_voxels > 0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("extend t = ", options.half_thickness_voxels, ", R = ", options.radius_voxels,
                     " and r = ", options.scvd_radius_voxels, " must all be positive"));
  }
  if (within != nullptr && !(within->dims() == patch.set.dims())) {
    return absl::InvalidArgumentError("extend: the original image's dims differ from the patch's");
  }
  ExtendResult out;
  out.patch = patch;
  if (patch.set.empty()) return out;
  for (int round = 0; round < options.max_rounds; ++round) {
    const Progress p =
        progress.Sub(double(round) / options.max_rounds, double(round + 1) / options.max_rounds);
    SM_ASSIGN_OR_RETURN(std::vector<Claim> claims,
                        Round(out.patch, options, within, p, round == 0 ? first_round : nullptr));
    if (claims.empty()) break;
    out.added += claims.size();
    ++out.rounds;
    out.patch = Merge(out.patch, claims);
  }
  SM_RETURN_IF_ERROR(progress.Update(1.0));
  return out;
}

}  // namespace sheetmesh
