#pragma once
// The campaign's randomness (docs/campaign.md): std::mt19937_64 and the draws of
// core/seeded_random.h, so that a seed gives the same plan and the same simulated answers on
// any machine.
//
// Each use gets a substream of its own: substream_seed(seed, a, b, c) mixes the campaign seed
// with the participant's index, the block's index and a purpose tag (SplitMix64's finaliser),
// so that adding a block or a participant does not shift the draws of the others, and the
// plan's randomness stays apart from the simulated participants'.
// Thread safety: free functions; a generator belongs to its caller.
#include <cstdint>
#include <random>

#include "core/seeded_random.h"

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

inline std::uint64_t substream_seed(std::uint64_t seed, std::uint64_t a, std::uint64_t b,
                                    Purpose purpose) {
  std::uint64_t x = mix64(seed);
  x = mix64(x ^ (a * 0xD1B54A32D192ED03ULL));
  x = mix64(x ^ (b * 0xABC98388FB8FAC03ULL));
  return mix64(x ^ static_cast<std::uint64_t>(purpose));
}

}  // namespace doorbench::study
