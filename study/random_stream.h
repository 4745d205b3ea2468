#pragma once
// The campaign's randomness (docs/campaign.md): std::mt19937_64, whose output the C++
// standard fixes, with the bounded and continuous draws done here rather than by library
// distributions (whose output the standard leaves to each implementation), so that a seed
// gives the same plan and the same simulated answers on any machine.
//
// Each use gets a substream of its own: substream_seed(seed, a, b, c) mixes the campaign seed
// with the participant's index, the block's index and a purpose tag (SplitMix64's finaliser),
// so that adding a block or a participant does not shift the draws of the others, and the
// plan's randomness stays apart from the simulated participants'.
// Thread safety: free functions; a generator belongs to its caller.
#include <cmath>
#include <cstdint>
#include <random>

namespace doorbench::study {

// The purposes a substream is drawn for (the last argument of substream_seed).
enum class Purpose : std::uint64_t {
  kBlockOrder = 1,
  kTrialOrder = 2,
  kTuneStart = 3,
  kParticipantModel = 4,
  kAnswer = 5,
  kSquareLabels = 6,  // a block's relabelling of its Williams design (campaign-wide)
};

inline std::uint64_t mix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

inline std::uint64_t substream_seed(std::uint64_t seed, std::uint64_t a, std::uint64_t b,
                                    Purpose purpose) {
  std::uint64_t x = mix64(seed);
  x = mix64(x ^ (a * 0xD1B54A32D192ED03ULL));
  x = mix64(x ^ (b * 0xABC98388FB8FAC03ULL));
  return mix64(x ^ static_cast<std::uint64_t>(purpose));
}

// Uniform on 0..bound−1 (bound > 0) without modulo bias: the low 2^64 mod bound outputs are
// rejected.
inline std::uint64_t uniform_below(std::mt19937_64& random, std::uint64_t bound) {
  const std::uint64_t reject_below = (0 - bound) % bound;
  for (;;) {
    const std::uint64_t x = random();
    if (x >= reject_below) return x % bound;
  }
}

// Uniform on (0, 1): the top 53 bits, offset by half a step (never 0 or 1).
inline double uniform_open01(std::mt19937_64& random) {
  return (static_cast<double>(random() >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

// Standard normal by the Box–Muller transform (one of the pair used).
inline double standard_normal(std::mt19937_64& random) {
  const double u1 = uniform_open01(random);
  const double u2 = uniform_open01(random);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

// Fisher–Yates shuffle with uniform_below.
template <typename Vector>
void shuffle_in_place(Vector& items, std::mt19937_64& random) {
  for (std::size_t i = items.size(); i > 1; --i) {
    const std::size_t j = uniform_below(random, i);
    typename Vector::value_type held = items[i - 1];  // (also for std::vector<bool>)
    items[i - 1] = items[j];
    items[j] = held;
  }
}

}  // namespace doorbench::study
