#pragma once
// Seed derivation of fast/'s Monte Carlo studies and generated cases
// (internal header).
#include <cstdint>

namespace fdsid::numerics {

/// SplitMix64's output function (Steele, Lea and Flood, "Fast splittable
/// pseudorandom number generators", OOPSLA 2014): a bijection of 64-bit words
/// whose outputs for consecutive inputs are statistically independent; used to
/// derive one generator's seed per run, case or stream from the user's seed.
inline std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace fdsid::numerics
