// The world generator's random stream (private to whiskeye_worldgen).
#pragma once

#include "whiskeye/sim/world_generator.h"

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace whiskeye::sim::worldgen {

// splitmix64: fully specified, so a world seed gives the same world on every platform.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform(double a, double b) { return a + (b - a) * (static_cast<double>(next() >> 11) * 0x1.0p-53); }
  double uniform(const Range& r) { return uniform(r.min, r.max); }
  // Inclusive.
  int integer(int a, int b) { return a + static_cast<int>(next() % static_cast<uint64_t>(b - a + 1)); }
  int integer(const Range& r) { return integer(static_cast<int>(std::lround(r.min)), static_cast<int>(std::lround(r.max))); }
  bool chance(double p) { return uniform(0.0, 1.0) < p; }
  template <typename T>
  void shuffle(std::vector<T>& v) {
    for (std::size_t i = v.size(); i > 1; --i) std::swap(v[i - 1], v[static_cast<std::size_t>(next() % i)]);
  }

 private:
  uint64_t state_;
};

}  // namespace whiskeye::sim::worldgen
