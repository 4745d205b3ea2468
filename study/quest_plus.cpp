#include "study/quest_plus.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace doorbench::study {
namespace {

constexpr double kQuestZ75 = 0.6744897501960817;  // Φ⁻¹(0.75)

// n values log-spaced over [low, high] (one value: low).
std::vector<double> quest_log_spaced(double low, double high, int n) {
  std::vector<double> values;
  for (int i = 0; i < n; ++i) {
    const double u = n == 1 ? 0.0 : static_cast<double>(i) / (n - 1);
    values.push_back(std::exp(std::log(low) + u * (std::log(high) - std::log(low))));
  }
  return values;
}

double quest_entropy_of(const std::vector<double>& weights, double total) {
  double h = 0.0;
  for (double p : weights) {
    if (p > 0.0) h -= (p / total) * std::log(p / total);
  }
  return h;
}

}  // namespace

QuestPlusGrid quest_plus_grid(const Block& block) {
  QuestPlusGrid grid;
  const double low = block.min_level - 1.0, high = block.max_level - 1.0;
  for (double delta : quest_log_spaced(low, high, block.quest_levels)) {
    const double level = std::round((1.0 + delta) * 1e4) / 1e4;  // as jnd_stimulus_name writes it
    if (level > 1.0 && (grid.levels.empty() || level > grid.levels.back()))
      grid.levels.push_back(level);
  }
  grid.thresholds = quest_log_spaced(low, high, block.quest_thresholds);
  grid.slopes.assign(kQuestPlusSlopes.begin(), kQuestPlusSlopes.end());
  grid.lapse = block.lapse;
  return grid;
}

QuestPlus::QuestPlus(QuestPlusGrid grid) : grid_(std::move(grid)) {
  if (grid_.levels.empty() || grid_.thresholds.empty() || grid_.slopes.empty()) {
    throw std::invalid_argument("QUEST+: an empty grid");
  }
  if (!(grid_.lapse >= 0.0 && grid_.lapse < 1.0))
    throw std::invalid_argument("QUEST+: lapse must be in [0, 1)");
  const auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  for (double level : grid_.levels) {
    if (!(level > 1.0 && std::isfinite(level)))
      throw std::invalid_argument("QUEST+: a level not above 1");
  }
  if (!std::all_of(grid_.thresholds.begin(), grid_.thresholds.end(), positive) ||
      !std::all_of(grid_.slopes.begin(), grid_.slopes.end(), positive)) {
    throw std::invalid_argument("QUEST+: a threshold or slope not above 0");
  }
  const std::size_t nt = grid_.thresholds.size(), ns = grid_.slopes.size();
  stronger_.resize(grid_.levels.size() * nt * ns);
  for (std::size_t l = 0; l < grid_.levels.size(); ++l) {
    const double x = std::log(grid_.levels[l]);
    for (std::size_t t = 0; t < nt; ++t) {
      const double at75 = std::log1p(grid_.thresholds[t]);
      for (std::size_t s = 0; s < ns; ++s) {
        const double spread = at75 / (kQuestZ75 * grid_.slopes[s]);
        const double pse = at75 - kQuestZ75 * spread;
        const double f = 0.5 * std::erfc(-(x - pse) / spread / std::sqrt(2.0));
        stronger_[(l * nt + t) * ns + s] = grid_.lapse / 2.0 + (1.0 - grid_.lapse) * f;
      }
    }
  }
  posterior_.assign(nt * ns, 1.0 / static_cast<double>(nt * ns));
}

double QuestPlus::probability(std::size_t level, std::size_t t, std::size_t s) const {
  const std::size_t nt = grid_.thresholds.size(), ns = grid_.slopes.size();
  return stronger_.at((level * nt + t) * ns + s);
}

std::vector<double> QuestPlus::expected_entropies() const {
  const std::size_t n = posterior_.size();
  std::vector<double> result, yes(n), no(n);
  for (std::size_t l = 0; l < grid_.levels.size(); ++l) {
    double p_yes = 0.0, p_no = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const double p = stronger_[l * n + i];
      yes[i] = posterior_[i] * p;
      no[i] = posterior_[i] * (1.0 - p);
      p_yes += yes[i];
      p_no += no[i];
    }
    double expected = 0.0;
    if (p_yes > 0.0) expected += p_yes * quest_entropy_of(yes, p_yes);
    if (p_no > 0.0) expected += p_no * quest_entropy_of(no, p_no);
    result.push_back(expected);
  }
  return result;
}

std::size_t QuestPlus::next_level() const {
  const std::vector<double> entropies = expected_entropies();
  return static_cast<std::size_t>(std::min_element(entropies.begin(), entropies.end()) -
                                  entropies.begin());
}

void QuestPlus::update(std::size_t level, bool stronger) {
  if (level >= grid_.levels.size()) throw std::out_of_range("QUEST+: no such level");
  const std::size_t n = posterior_.size();
  double total = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double p = stronger_[level * n + i];
    posterior_[i] *= stronger ? p : 1.0 - p;
    total += posterior_[i];
  }
  if (!(total > 0.0))
    throw std::invalid_argument("QUEST+: an answer the model gives probability 0");
  for (double& p : posterior_) p /= total;
  ++trials_;
}

QuestPlusEstimate QuestPlus::estimate(double mass) const {
  if (!(mass > 0.0 && mass < 1.0))
    throw std::invalid_argument("QUEST+: the credible mass must be in (0, 1)");
  const std::size_t nt = grid_.thresholds.size(), ns = grid_.slopes.size();
  std::vector<double> marginal(nt, 0.0), log_w(nt);
  double mean = 0.0;
  for (std::size_t t = 0; t < nt; ++t) {
    for (std::size_t s = 0; s < ns; ++s) marginal[t] += posterior_[t * ns + s];
    log_w[t] = std::log(grid_.thresholds[t]);
    mean += marginal[t] * log_w[t];
  }
  // Cell edges half-way between grid points (the end cells as wide as their neighbours').
  std::vector<double> edges(nt + 1);
  for (std::size_t t = 1; t < nt; ++t) edges[t] = 0.5 * (log_w[t - 1] + log_w[t]);
  const double half = nt > 1 ? 0.5 * (log_w[1] - log_w[0]) : 0.0;
  edges[0] = log_w[0] - half;
  edges[nt] = log_w[nt - 1] + (nt > 1 ? 0.5 * (log_w[nt - 1] - log_w[nt - 2]) : 0.0);
  const auto quantile = [&](double q) {
    double cumulative = 0.0;
    for (std::size_t t = 0; t < nt; ++t) {
      if (cumulative + marginal[t] >= q && marginal[t] > 0.0) {
        return edges[t] + (q - cumulative) / marginal[t] * (edges[t + 1] - edges[t]);
      }
      cumulative += marginal[t];
    }
    return edges[nt];
  };
  QuestPlusEstimate result;
  result.weber_fraction = std::exp(mean);
  result.ci_low = std::exp(quantile((1.0 - mass) / 2.0));
  result.ci_high = std::exp(quantile((1.0 + mass) / 2.0));
  result.trials = trials_;
  return result;
}

QuestPlus quest_plus_replay(const Block& block, const std::vector<bool>& stronger) {
  QuestPlus quest(quest_plus_grid(block));
  for (bool answer : stronger) quest.update(quest.next_level(), answer);
  return quest;
}

double quest_plus_level(const Block& block, const std::vector<bool>& stronger) {
  const QuestPlus quest = quest_plus_replay(block, stronger);
  return quest.grid().levels[quest.next_level()];
}

QuestPlusEstimate quest_plus_estimate(const Block& block, const std::vector<bool>& stronger) {
  return quest_plus_replay(block, stronger).estimate();
}

}  // namespace doorbench::study
