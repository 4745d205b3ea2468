#include "study/staircase.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace doorbench::study {
namespace {

struct Track {
  std::vector<double> levels;     // levels[i]: the level of trial i (one more than answers)
  std::vector<double> reversals;  // levels where the direction changed
};

Track track_of(const Block& block, const std::vector<bool>& correct) {
  Track track;
  double increment = block.start_level - 1.0;
  const double low = block.min_level - 1.0, high = block.max_level - 1.0;
  int run = 0, direction = 0;
  track.levels.push_back(1.0 + increment);
  for (bool right : correct) {
    int step = 0;
    if (right) {
      if (++run >= block.down) {
        step = -1;
        run = 0;
      }
    } else {
      step = +1;
      run = 0;
    }
    if (step != 0) {
      if (direction != 0 && step != direction) track.reversals.push_back(1.0 + increment);
      direction = step;
      increment = step < 0 ? increment / block.step_factor : increment * block.step_factor;
      increment = std::clamp(increment, low, high);
    }
    track.levels.push_back(1.0 + increment);
  }
  return track;
}

}  // namespace

double staircase_level(const Block& block, const std::vector<bool>& correct) {
  return track_of(block, correct).levels.back();
}

double staircase_threshold(const Block& block, const std::vector<bool>& correct) {
  const Track track = track_of(block, correct);
  std::vector<double> reversals = track.reversals;
  if (reversals.size() < 2) return std::numeric_limits<double>::quiet_NaN();
  if (reversals.size() > 4) reversals.erase(reversals.begin(), reversals.begin() + 2);
  if (reversals.size() > 6) reversals.erase(reversals.begin(), reversals.end() - 6);
  double log_sum = 0.0;
  for (double level : reversals) log_sum += std::log(level - 1.0);
  return 1.0 + std::exp(log_sum / static_cast<double>(reversals.size()));
}

}  // namespace doorbench::study
