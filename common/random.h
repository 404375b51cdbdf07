// A small seeded random generator (SplitMix64) with portable distributions, so that a
// given seed gives the same phantom and the same SCVD on every machine and library.
#ifndef SHEETMESH_COMMON_RANDOM_H_
#define SHEETMESH_COMMON_RANDOM_H_

#include <cstdint>

namespace sheetmesh {

// Not thread-safe; one per thread.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}

  uint64_t Next() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1).
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
  // Uniform in [lo, hi).
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  // Uniform integer in [0, n). REQUIRES: n > 0.
  uint64_t Below(uint64_t n) {
    // Multiply-shift keeps the bias below 2^-64 * n, negligible for our n.
    return static_cast<uint64_t>((static_cast<unsigned __int128>(Next()) * n) >> 64);
  }

 private:
  uint64_t state_;
};

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_RANDOM_H_
