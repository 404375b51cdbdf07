#include "worker/pipeline/scvd/local_seeds.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "absl/container/flat_hash_map.h"

namespace sheetmesh {

double PositionHash(const Index3& p, uint64_t seed) {
  // 21 bits per coordinate: positions below 2^21 (2 M voxels a side) pack without loss.
  const uint64_t key = (uint64_t(uint32_t(p.z)) & 0x1FFFFF) << 42 |
                       (uint64_t(uint32_t(p.y)) & 0x1FFFFF) << 21 |
                       (uint64_t(uint32_t(p.x)) & 0x1FFFFF);
  uint64_t z = key + seed * 0x9e3779b97f4a7c15ULL + 0x632be59bd9b4e019ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53;
}

double ExclusionRadius(double voxels, double thickness, bool columns) {
  constexpr double kPi = std::numbers::pi;
  const double t = std::max(thickness, 1.0);
  if (columns) return std::sqrt(voxels / t / kPi);
  if (voxels <= 4.0 / 3.0 * kPi * std::pow(t / 2, 3)) return std::cbrt(3 * voxels / (4 * kPi));
  return std::sqrt(voxels / (kPi * t) + t * t / 12);
}

namespace {

// A cube of the draw's grid, by its index along each axis (global positions are not
// negative, nor are these).
struct CubeKey {
  int64_t x, y, z;
  friend bool operator==(const CubeKey&, const CubeKey&) = default;
  template <typename H>
  friend H AbslHashValue(H h, const CubeKey& k) {
    return H::combine(std::move(h), k.x, k.y, k.z);
  }
};

struct Candidate {
  double hash;
  Index3 position;
  uint32_t node;
};

bool Before(const Candidate& a, const Candidate& b) {
  if (a.hash != b.hash) return a.hash < b.hash;
  const Index3 &p = a.position, &q = b.position;
  if (p.z != q.z) return p.z < q.z;
  if (p.y != q.y) return p.y < q.y;
  return p.x < q.x;
}

struct Cube {
  double voxels = 0;
  int count = 0;                 // generators it gets
  std::vector<Candidate> least;  // its nodes of least hash (at most a few per generator)
};

}  // namespace

std::vector<uint32_t> StratifiedDraw(
    const LocalDraw& draw,
    const std::function<void(const std::function<void(uint32_t, const Index3&, double)>&)>&
        for_each_node) {
  const double side = 2 * draw.spacing;
  auto key = [&](const Index3& p) {
    return CubeKey{static_cast<int64_t>(std::floor(p.x / side)),
                   static_cast<int64_t>(std::floor(p.y / side)),
                   static_cast<int64_t>(std::floor(p.z / side))};
  };
  absl::flat_hash_map<CubeKey, Cube> cubes;
  for_each_node([&](uint32_t, const Index3& p, double voxels) { cubes[key(p)].voxels += voxels; });
  // The dither of each cube: its own hash, decorrelated from the nodes'.
  const uint64_t cube_seed = draw.seed ^ 0x5bd1e9955bd1e995ULL;
  for (auto& [k, cube] : cubes) {
    const Index3 at{static_cast<int32_t>(k.x), static_cast<int32_t>(k.y),
                    static_cast<int32_t>(k.z)};
    cube.count =
        static_cast<int>(std::floor(cube.voxels * draw.per_voxel + PositionHash(at, cube_seed)));
  }
  // Each cube's nodes of least hash: enough to find its generators spaced apart.
  auto keep = [](const Cube& c) { return static_cast<size_t>(4 * c.count + 8); };
  for_each_node([&](uint32_t n, const Index3& p, double) {
    Cube& cube = cubes[key(p)];
    if (cube.count == 0) return;
    cube.least.push_back({PositionHash(p, draw.seed), p, n});
    if (cube.least.size() >= 2 * keep(cube)) {
      std::nth_element(cube.least.begin(), cube.least.begin() + keep(cube), cube.least.end(),
                       Before);
      cube.least.resize(keep(cube));
    }
  });
  const double apart = draw.spacing * draw.spacing;
  std::vector<uint32_t> chosen;
  for (auto& [k, cube] : cubes) {
    if (cube.count == 0) continue;
    std::sort(cube.least.begin(), cube.least.end(), Before);
    std::vector<const Candidate*> mine;
    std::vector<uint8_t> taken(cube.least.size(), 0);
    for (size_t i = 0; i < cube.least.size() && static_cast<int>(mine.size()) < cube.count; ++i) {
      const Index3& p = cube.least[i].position;
      const bool spaced = std::all_of(mine.begin(), mine.end(), [&](const Candidate* c) {
        const double dx = c->position.x - p.x, dy = c->position.y - p.y, dz = c->position.z - p.z;
        return dx * dx + dy * dy + dz * dz >= apart;
      });
      if (spaced) {
        mine.push_back(&cube.least[i]);
        taken[i] = 1;
      }
    }
    // Too few nodes apart (a cube the sheet only grazes): the least of the rest.
    for (size_t i = 0; i < cube.least.size() && static_cast<int>(mine.size()) < cube.count; ++i) {
      if (!taken[i]) mine.push_back(&cube.least[i]);
    }
    for (const Candidate* c : mine) chosen.push_back(c->node);
  }
  std::sort(chosen.begin(), chosen.end());
  return chosen;
}

}  // namespace sheetmesh
