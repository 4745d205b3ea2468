#pragma once
// Simulated ratings from the cumulative-logit mixed model with a known truth, for the
// ratings tests (R comparison, coverage): logit P(Y <= k) = theta_k - (beta_v + sigma u_i).
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "study/statistics/ratings.h"

namespace doorbench::testing {

struct RatingTruth {
  std::string attribute = "heavy";
  std::vector<double> thresholds{-2.0, -0.7, 0.5, 1.8};  // K - 1 of them: K = 5
  std::vector<double> effects{0.0, 0.8, -0.5, 1.5};      // per variant, the first at 0
  double participant_sd = 1.0;
  int participants = 12;
  int repetitions = 2;  // ratings of each variant per participant
};

inline std::string variant_name(std::size_t v) {
  return std::string("V").append(std::to_string(v + 1));
}
inline std::string participant_name(int i) {
  return std::string(i < 9 ? "P0" : "P").append(std::to_string(i + 1));
}

inline std::vector<study::RatingObservation> simulate_ratings(const RatingTruth& truth,
                                                              std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const int k = static_cast<int>(truth.thresholds.size()) + 1;
  std::vector<study::RatingObservation> out;
  for (int i = 0; i < truth.participants; ++i) {
    const double u = truth.participant_sd * normal(random);
    for (int r = 0; r < truth.repetitions; ++r) {
      for (std::size_t v = 0; v < truth.effects.size(); ++v) {
        const double eta = truth.effects[v] + u;
        const double draw = uniform(random);
        int rating = k;
        for (int j = 0; j < k - 1; ++j) {
          if (draw <= 1.0 / (1.0 + std::exp(-(truth.thresholds[j] - eta)))) {
            rating = j + 1;
            break;
          }
        }
        out.push_back({participant_name(i), truth.attribute, k, variant_name(v), rating});
      }
    }
  }
  return out;
}

}  // namespace doorbench::testing
