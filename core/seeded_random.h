#pragma once
// Seeded random draws that give the same numbers on every machine: std::mt19937_64, whose
// output the C++ standard fixes, with the bounded and continuous draws done here rather than
// by the library's distributions (whose output the standard leaves to each implementation).
//
//   mix64(x)                   SplitMix64's finaliser: a seed mixed into a well-spread one
//   uniform_below(g, bound)    uniform on 0..bound−1 (bound > 0), without modulo bias
//   uniform_open01(g)          uniform on (0, 1), never 0 or 1
//   standard_normal(g)         a standard normal draw (Box–Muller)
//   shuffle_in_place(v, g)     a Fisher–Yates shuffle with uniform_below
//
// Thread safety: free functions; a generator belongs to its caller.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <random>

namespace doorbench {

inline std::uint64_t mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// The low 2^64 mod bound outputs are rejected, so every value is equally likely.
inline std::uint64_t uniform_below(std::mt19937_64& random, std::uint64_t bound) {
  const std::uint64_t reject_below = (0 - bound) % bound;
  for (;;) {
    const std::uint64_t x = random();
    if (x >= reject_below) return x % bound;
  }
}

// The top 53 bits, offset by half a step.
inline double uniform_open01(std::mt19937_64& random) {
  return (static_cast<double>(random() >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

// Box–Muller, one of the pair used.
inline double standard_normal(std::mt19937_64& random) {
  const double u1 = uniform_open01(random);
  const double u2 = uniform_open01(random);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

template <typename Vector>
void shuffle_in_place(Vector& items, std::mt19937_64& random) {
  for (std::size_t i = items.size(); i > 1; --i) {
    const std::size_t j = uniform_below(random, i);
    typename Vector::value_type held = items[i - 1];  // (also for std::vector<bool>)
    items[i - 1] = items[j];
    items[j] = held;
  }
}

}  // namespace doorbench
