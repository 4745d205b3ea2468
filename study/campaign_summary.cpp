#include "study/campaign_summary.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "study/campaign_plan.h"
#include "study/campaign_run.h"
#include "study/quest_plus.h"
#include "study/staircase.h"

namespace doorbench::study {
namespace {

std::string format(const char* pattern, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, pattern, value);
  return buffer;
}

// "; median threshold J*1.12 over 3 participants; QUEST+ posterior mean Weber fraction
// [95 % credible interval]: P01 0.12 [0.08, 0.18], ..." (study/quest_plus.h).
std::string quest_plus_summary(const Block& block,
                               const std::map<std::string, std::vector<bool>>& tracks) {
  std::vector<double> means;
  std::string each;
  for (const auto& [participant, track] : tracks) {
    const QuestPlusEstimate estimate = quest_plus_estimate(block, track);
    means.push_back(estimate.weber_fraction);
    each += std::string(each.empty() ? " " : ", ").append(participant).append(" ") +
            format("%.3f", estimate.weber_fraction) + " [" + format("%.3f", estimate.ci_low) +
            ", " + format("%.3f", estimate.ci_high) + "]";
  }
  if (means.empty()) return "; no answers for a threshold";
  std::sort(means.begin(), means.end());
  const double median = means.size() % 2
                            ? means[means.size() / 2]
                            : 0.5 * (means[means.size() / 2 - 1] + means[means.size() / 2]);
  return "; median threshold " + jnd_stimulus_name(block.parameter, 1.0 + median) + " over " +
         std::to_string(means.size()) +
         " participants; QUEST+ posterior mean Weber fraction [95 % credible interval]:" + each;
}

// The rows of each participant's latest attempt.
std::vector<std::size_t> latest_rows(const TrialsTable& trials) {
  std::map<std::string, int> latest;
  for (std::size_t r = 0; r < trials.rows.size(); ++r) {
    int& attempt = latest[trials.value(r, "participant")];
    attempt = std::max(attempt, std::stoi(trials.value(r, "attempt")));
  }
  std::vector<std::size_t> rows;
  for (std::size_t r = 0; r < trials.rows.size(); ++r) {
    if (std::stoi(trials.value(r, "attempt")) == latest[trials.value(r, "participant")])
      rows.push_back(r);
  }
  return rows;
}

std::string summary_of(const Block& block, const TrialsTable& trials,
                       const std::vector<std::size_t>& rows) {
  std::string line = block.name + " (" + std::string(to_string(block.type)) + "): ";
  std::map<std::string, double> sum;
  std::map<std::string, int> count;
  std::map<std::string, std::vector<bool>> tracks;
  int answers = 0;
  for (std::size_t r : rows) {
    if (trials.value(r, "block") != block.name) continue;
    ++answers;
    const std::string& first = trials.value(r, "first");
    const std::string& second = trials.value(r, "second");
    const std::string& answer = trials.value(r, "answer");
    if (block.type == BlockType::kPair) {
      ++count[answer == "same" ? "same" : answer == "1" ? first : second];
    } else if (block.type == BlockType::kRating) {
      const std::string& question = trials.value(r, "question");
      const std::string attribute = question.substr(7, question.rfind(':') - 7);
      const std::size_t space = answer.find(' ');
      sum[attribute + " " + first] += std::stod(answer.substr(0, space));
      sum[attribute + " " + second] += std::stod(answer.substr(space + 1));
      ++count[attribute + " " + first];
      ++count[attribute + " " + second];
    } else if (block.type == BlockType::kJnd) {
      const bool right = names_comparison(first, second, answer, block.parameter);
      if (block.method != JndMethod::kConstantStimuli) {
        tracks[trials.value(r, "participant")].push_back(right);
      } else {
        const std::string level = first == jnd_stimulus_name(block.parameter, 1.0) ? second : first;
        ++count[level];
        sum[level] += right;
      }
    }
  }
  line += std::to_string(answers) + " answers";
  if (block.type == BlockType::kTune)
    return line + " (one tuned door each, in sessions/P/aN/tNNN-tuned.json)";
  if (block.type == BlockType::kPair) {
    line += "; chosen:";
    for (const auto& [name, n] : count) line += " " + name + " " + std::to_string(n);
    return line;
  }
  if (block.type == BlockType::kRating) {
    line += "; mean rating (1.." + std::to_string(block.scale) + "):";
    for (const auto& [key, n] : count) line += " " + key + " " + format("%.1f", sum[key] / n) + ",";
    if (line.back() == ',') line.pop_back();
    return line;
  }
  if (block.method == JndMethod::kConstantStimuli) {
    line += "; comparison named stronger:";
    for (const auto& [level, n] : count)
      line += " " + level + " " + format("%.0f %%", 100.0 * sum[level] / n) + ",";
    if (line.back() == ',') line.pop_back();
    return line;
  }
  if (block.method == JndMethod::kQuestPlus) return line + quest_plus_summary(block, tracks);
  std::vector<double> thresholds;
  for (const auto& [participant, track] : tracks) {
    const double threshold = staircase_threshold(block, track);
    if (std::isfinite(threshold)) thresholds.push_back(threshold);
  }
  if (thresholds.empty()) return line + "; too few reversals for a threshold";
  std::sort(thresholds.begin(), thresholds.end());
  const double median =
      thresholds.size() % 2
          ? thresholds[thresholds.size() / 2]
          : 0.5 * (thresholds[thresholds.size() / 2 - 1] + thresholds[thresholds.size() / 2]);
  return line + "; median threshold " + jnd_stimulus_name(block.parameter, median) + " over " +
         std::to_string(thresholds.size()) + " participants";
}

}  // namespace

std::vector<std::string> block_summaries(const Campaign& campaign, const TrialsTable& trials) {
  const std::vector<std::size_t> rows = latest_rows(trials);
  std::vector<std::string> lines;
  for (const Block& block : campaign.blocks) lines.push_back(summary_of(block, trials, rows));
  return lines;
}

}  // namespace doorbench::study
