#pragma once
// Simulated "which felt stronger?" answers from a known psychometric function, for the
// thresholds tests (grid check, staircases, coverage).
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "study/statistics/thresholds.h"

namespace doorbench::testing {

struct ObserverTruth {
  double weber_fraction = 0.12;  // at the 75 % point of the lapse-free cumulative normal
  double pse = 0.0;
  double lapse = 0.03;
  // The spread of the cumulative normal on ln ratio that gives the Weber fraction.
  double spread() const { return std::log1p(weber_fraction) / 0.6744897501960817; }
  double probability(double level) const {
    const double f = 0.5 * std::erfc(-(level - pse) / spread() / std::sqrt(2.0));
    return lapse / 2.0 + (1.0 - lapse) * f;
  }
};

// Constant stimuli: each factor `repetitions` times, for `participants` participants.
inline std::vector<study::StrongerObservation> simulate_constant_stimuli(
    const ObserverTruth& truth, const std::vector<double>& factors, int repetitions,
    int participants, std::mt19937_64& random) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<study::StrongerObservation> out;
  for (int i = 0; i < participants; ++i) {
    int trial = 0;
    for (int r = 0; r < repetitions; ++r) {
      for (const double factor : factors) {
        const double level = std::log(factor);
        out.push_back({std::string("P").append(std::to_string(i + 1)), "jnd-constant", ++trial,
                       "J_d", "J_d*1.00", level, uniform(random) < truth.probability(level)});
      }
    }
  }
  return out;
}

// A 1-up-N-down staircase on ln ratio above the reference: starts at `start`, steps by
// `step` (ln units) down after N "stronger" answers in a row, up after one "not stronger".
inline std::vector<study::StrongerObservation> simulate_staircase(const ObserverTruth& truth,
                                                                  int down_rule, double start,
                                                                  double step, int trials,
                                                                  const std::string& participant,
                                                                  std::mt19937_64& random) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<study::StrongerObservation> out;
  double level = start;
  int run = 0;
  for (int t = 0; t < trials; ++t) {
    const bool stronger = uniform(random) < truth.probability(level);
    out.push_back({participant, "jnd-staircase", t + 1, "J_d", "J_d*1.00", level, stronger});
    if (stronger && ++run == down_rule) {
      level = std::max(level - step, step);
      run = 0;
    } else if (!stronger) {
      level += step;
      run = 0;
    }
  }
  return out;
}

}  // namespace doorbench::testing
