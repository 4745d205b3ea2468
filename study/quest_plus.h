#pragma once
// QUEST+ for a jnd block (docs/campaign.md, "QUEST+"): A. B. Watson, "QUEST+: A general
// multidimensional Bayesian adaptive psychometric method", Journal of Vision 17(3):10, 2017.
//
// Model: the analysis's 2-AFC "which felt stronger" function (study/statistics/thresholds.h)
// on the comparison's level x = ln(c / r):
//   P(comparison named stronger | x) = lapse / 2 + (1 - lapse) Φ((x - pse) / spread),
// written with two QUEST+ parameters:
//  - threshold w, a Weber fraction: the lapse-free Φ reaches 75 % at x = ln(1 + w);
//  - slope k (relative): spread = ln(1 + w) / (z75 · k), so pse = ln(1 + w) (1 - 1/k);
//    k = 1 is a curve through 50 % at the reference (an unbiased observer, the participant
//    model's own curve), k > 1 steeper, k < 1 shallower;
//  - lapse fixed (the block's `lapse`, default 0.03, the participant model's mean).
// Grids: w log-spaced over [min_level - 1, max_level - 1] (the campaign file's `thresholds`
// points, Block::quest_thresholds), k in kQuestPlusSlopes; prior uniform over that grid (so
// uniform in ln w). Stimuli: `stimuli` (Block::quest_levels) comparison levels 1 + Δ, Δ
// log-spaced over the same range, each rounded to the 4 decimals of its name in trials.csv
// (jnd_stimulus_name), so the level updated is the level shown.
//
// Each trial presents the stimulus that minimises the expected entropy (nats) of the
// posterior after the answer (the lowest level on a tie) and updates the posterior by the
// answer (Bayes). Everything is a pure function of the answers, so a resumed run that reads
// them back from trials.csv continues with the same levels.
//
// The estimate: the posterior mean of ln w (over the grid, marginal over k), reported as the
// Weber fraction w = exp(E[ln w]); its 95 % credible interval: the 2.5 % and 97.5 %
// quantiles of the marginal posterior of ln w, each grid point's mass spread evenly over its
// cell (half-way to its neighbours).
// Thread safety: QuestPlus objects are not shared between threads; free functions are pure.
#include <array>
#include <cstddef>
#include <vector>

#include "study/campaign_file.h"

namespace doorbench::study {

inline constexpr std::array<double, 5> kQuestPlusSlopes{0.5, 0.7071067811865476, 1.0,
                                                        1.4142135623730951, 2.0};

struct QuestPlusGrid {
  std::vector<double> levels;      // comparison levels c / r (> 1), ascending
  std::vector<double> thresholds;  // Weber fractions w (> 0), ascending
  std::vector<double> slopes;      // k (> 0)
  double lapse = 0.03;             // [0, 1)
};

// The grid of a quest+ jnd block (see above).
QuestPlusGrid quest_plus_grid(const Block& block);

struct QuestPlusEstimate {
  double weber_fraction = 0.0;         // exp(posterior mean of ln w)
  double ci_low = 0.0, ci_high = 0.0;  // 95 % credible interval of w
  int trials = 0;
};

class QuestPlus {
 public:
  // A uniform prior over the grid. std::invalid_argument for an empty grid or values out of
  // range (see QuestPlusGrid).
  explicit QuestPlus(QuestPlusGrid grid);
  // P(comparison named stronger) at levels[level] under thresholds[t], slopes[s].
  double probability(std::size_t level, std::size_t t, std::size_t s) const;
  // The expected posterior entropy (nats) after presenting each level, in the grid's order.
  std::vector<double> expected_entropies() const;
  // The index of the level to present next.
  std::size_t next_level() const;
  // Bayes update with the answer at levels[level]. std::out_of_range for a bad index.
  void update(std::size_t level, bool stronger);
  // The posterior, index t * slopes + s.
  const std::vector<double>& posterior() const { return posterior_; }
  // The estimate with a `mass` credible interval (0 < mass < 1).
  QuestPlusEstimate estimate(double mass = 0.95) const;
  const QuestPlusGrid& grid() const { return grid_; }

 private:
  QuestPlusGrid grid_;
  std::vector<double> stronger_;   // P(stronger), index (level * thresholds + t) * slopes + s
  std::vector<double> posterior_;  // normalised
  int trials_ = 0;
};

// The block's QUEST+ after `stronger` (the block's answers so far, true: the comparison was
// named stronger), replayed from the prior.
QuestPlus quest_plus_replay(const Block& block, const std::vector<bool>& stronger);
// The level of the next trial after those answers.
double quest_plus_level(const Block& block, const std::vector<bool>& stronger);
// The estimate after them (trials 0 and the prior's estimate when there are none).
QuestPlusEstimate quest_plus_estimate(const Block& block, const std::vector<bool>& stronger);

}  // namespace doorbench::study
