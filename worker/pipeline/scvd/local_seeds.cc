#include "worker/pipeline/scvd/local_seeds.h"

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

}  // namespace sheetmesh
