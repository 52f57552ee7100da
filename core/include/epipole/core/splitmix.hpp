#pragma once

// SplitMix64 (Steele, Lea and Flood, 2014): a tiny generator whose numbers are the same on every
// target and standard library (std::mt19937's are too, but its distributions are not), for what
// must be reproducible: RANSAC's samples, the simulated sensors' noise.
#include <cstdint>

namespace epipole {

class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // In [0, 1), 53 bits.
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  // In [0, n), n > 0 (the modulo's bias is below 2^-40 for the n used here).
  std::uint64_t below(std::uint64_t n) { return next() % n; }

 private:
  std::uint64_t state_;
};

}  // namespace epipole
