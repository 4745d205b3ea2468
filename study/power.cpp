#include "study/power.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>
#include <stdexcept>

#include "core/percentile.h"
#include "study/campaign_plan.h"
#include "study/campaign_run.h"
#include "study/quest_plus.h"
#include "study/random_stream.h"
#include "study/staircase.h"
#include "study/statistics/binomial.h"

namespace doorbench::study {
namespace {

struct Tally {
  long a = 0, b = 0;  // successes of each side
};

std::string pair_key(const std::string& x, const std::string& y) {
  return x < y ? x + " vs " + y : y + " vs " + x;
}

// One panel's tallies: key "block|question|what" -> counts; staircase thresholds per block.
void run_panel(const Campaign& campaign, const Plan& plan, std::uint64_t panel_seed,
               const PowerOptions& options, std::map<std::string, Tally>& tallies,
               std::map<std::string, std::vector<double>>& thresholds) {
  StimulusMaker maker(campaign);
  std::ostringstream ignored;
  for (std::size_t p = 0; p < campaign.participants.size(); ++p) {
    SimulatedRespondent respondent(substream_seed(panel_seed, p, 0, Purpose::kParticipantModel),
                                   maker.base(), 1, options.participant);
    std::map<std::string, std::vector<bool>> staircase;
    for (const PlanRow& row : plan.of(campaign.participants[p])) {
      const Block& block = block_of(campaign, row);
      if (block.type == BlockType::kTune) continue;
      auto [first, second] = maker.make(row, staircase[block.name]);
      const std::string answer = respondent.answer(row, first, second, ignored);
      const std::string prefix = block.name + "|" + row.question + "|";
      if (block.type == BlockType::kPair) {
        if (answer == "same") continue;
        const std::string chosen = answer == "1" ? first.name : second.name;
        Tally& tally = tallies[prefix + pair_key(first.name, second.name)];
        (chosen == std::min(first.name, second.name) ? tally.a : tally.b) += 1;
      } else if (block.type == BlockType::kRating) {
        const int r1 = std::stoi(answer.substr(0, answer.find(' ')));
        const int r2 = std::stoi(answer.substr(answer.find(' ') + 1));
        if (r1 == r2) continue;
        const std::string higher = r1 > r2 ? first.name : second.name;
        Tally& tally = tallies[prefix + pair_key(first.name, second.name)];
        (higher == std::min(first.name, second.name) ? tally.a : tally.b) += 1;
      } else {
        const bool right = names_comparison(first.name, second.name, answer, block.parameter);
        staircase[block.name].push_back(right);
        if (block.method == JndMethod::kConstantStimuli) {
          const std::string level =
              first.name == jnd_stimulus_name(block.parameter, 1.0) ? second.name : first.name;
          Tally& tally = tallies[prefix + "level " + level];
          (right ? tally.a : tally.b) += 1;
        }
      }
    }
    for (const Block& block : campaign.blocks) {
      if (block.type == BlockType::kJnd && block.method != JndMethod::kConstantStimuli &&
          !staircase[block.name].empty()) {
        const double threshold =
            block.method == JndMethod::kStaircase
                ? staircase_threshold(block, staircase[block.name])
                : 1.0 + quest_plus_estimate(block, staircase[block.name]).weber_fraction;
        if (std::isfinite(threshold)) thresholds[block.name].push_back(threshold);
      }
    }
  }
}

}  // namespace

std::pair<double, double> wilson_interval(int k, int n) {
  if (n <= 0) return {0.0, 1.0};
  const double z = 1.959963984540054, p = static_cast<double>(k) / n, z2n = z * z / n;
  const double centre = (p + z2n / 2.0) / (1.0 + z2n);
  const double half = z * std::sqrt(p * (1.0 - p) / n + z2n / (4.0 * n)) / (1.0 + z2n);
  return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

std::string PowerOptions::validate() const {
  if (panels < 1 || panels > 100000)
    return "panels must be 1 to 100000, got " + std::to_string(panels);
  if (!(alpha > 0.0 && alpha < 1.0)) return "alpha must be between 0 and 1";
  return participant.validate();
}

std::string PowerLine::text() const {
  char buffer[256];
  if (is_threshold) {
    std::snprintf(buffer, sizeof buffer,
                  "%s, %s: median threshold %.3f (panels' 5-95 %%: %.3f-%.3f) over %d panels",
                  block.c_str(), question.c_str(), threshold_median, threshold_p05, threshold_p95,
                  panels);
  } else {
    std::snprintf(buffer, sizeof buffer,
                  "%s, %s, %s: detected in %d of %d panels, %.0f %% (95 %% interval %.0f-%.0f %%)",
                  block.c_str(), question.c_str(), what.c_str(), detected, panels, 100.0 * rate,
                  100.0 * low, 100.0 * high);
  }
  return buffer;
}

std::vector<PowerLine> simulate_power(const Campaign& campaign, std::uint64_t seed,
                                      const PowerOptions& options) {
  if (const std::string problem = options.validate(); !problem.empty())
    throw std::invalid_argument("power: " + problem);
  const Plan plan = make_plan(campaign, seed);
  std::map<std::string, PowerLine> lines;
  std::map<std::string, std::vector<double>> medians;
  for (int panel = 0; panel < options.panels; ++panel) {
    std::map<std::string, Tally> tallies;
    std::map<std::string, std::vector<double>> thresholds;
    run_panel(campaign, plan, substream_seed(seed, 1000000 + panel, 0, Purpose::kParticipantModel),
              options, tallies, thresholds);
    for (const auto& [key, tally] : tallies) {
      PowerLine& line = lines[key];
      const std::size_t bar1 = key.find('|'), bar2 = key.find('|', bar1 + 1);
      line.block = key.substr(0, bar1);
      line.question = key.substr(bar1 + 1, bar2 - bar1 - 1);
      line.what = key.substr(bar2 + 1);
      ++line.panels;
      if (binomial_two_sided_p(tally.a, tally.a + tally.b) < options.alpha) ++line.detected;
    }
    for (const auto& [block, values] : thresholds)
      medians[block].push_back(percentile(values, 0.5));
  }
  std::vector<PowerLine> result;
  for (auto& [key, line] : lines) {
    line.panels = options.panels;  // a panel with no answers for it detected nothing
    line.rate = static_cast<double>(line.detected) / line.panels;
    std::tie(line.low, line.high) = wilson_interval(line.detected, line.panels);
    result.push_back(line);
  }
  for (const auto& [block, values] : medians) {
    PowerLine line;
    line.block = block;
    const Block& jnd = block_of(campaign, PlanRow{"", block, 0, "", "", "", 0});
    line.question = "stronger:" + jnd.parameter +
                    (jnd.method == JndMethod::kQuestPlus ? " (quest+)" : " (staircase)");
    line.is_threshold = true;
    line.panels = static_cast<int>(values.size());
    line.threshold_median = percentile(values, 0.5);
    line.threshold_p05 = percentile(values, 0.05);
    line.threshold_p95 = percentile(values, 0.95);
    result.push_back(line);
  }
  return result;
}

}  // namespace doorbench::study
