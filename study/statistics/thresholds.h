#pragma once
// Thresholds (docs/campaign.md, "Ratings and thresholds"): what difference in one parameter
// a participant can feel, from `jnd` blocks ("which felt stronger?").
//
// Psychometric function (Wichmann & Hill 2001), on the comparison's level x = ln(c / r), c
// and r the comparison's and the reference's factors on the parameter:
//
//   P(comparison felt stronger | x) = lapse / 2 + (1 - lapse) F((x - pse) / spread),
//
// F the standard normal CDF (cumulative normal) or the Gumbel CDF 1 - exp(-exp(z)) (the
// Weibull in c / r), a lapse being an answer at random (half of them "stronger"), lapse in
// [0, max_lapse]. Fitted by maximum likelihood (binomial). The JND is read on the lapse-free
// F: the level where F reaches the criterion (75 %) minus the level where it reaches 50 %
// (the PSE), as a Weber fraction exp(that) - 1. Its interval is the profile-likelihood one
// (every other parameter maximised out; the chi-square(1) cut), which can be open above
// (ci_high infinite) when the data do not bound the spread.
//
// Staircases (Levitt 1971): a participant's block whose comparisons all lie on one side of
// the reference and whose level moves away from the reference only after a "not stronger"
// answer and towards it only after a "stronger" one is a staircase (or any block named in
// the options). Its threshold is the mean of the last k reversal levels (ln c / r), as a
// Weber fraction, tracking P(correct) = 0.5^(1/N) for the 1-up-N-down rule its moves show;
// its interval is a t interval over those reversals (treating them as independent, which
// they are not quite: take it as indicative). It is also fitted as above.
//
// Errors: std::invalid_argument for invalid options or too few trials, naming the group;
// the trials adapter throws TrialsTableError naming the file, line and field.
// Thread safety: pure functions without shared state.
#include <array>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "study/trials_table.h"

namespace doorbench::study {

// One "which felt stronger?" trial.
struct StrongerObservation {
  std::string participant;
  std::string block;
  int trial = 0;          // order within the participant's block
  std::string parameter;  // e.g. "J_d"
  std::string reference;  // the reference's label, e.g. "J_d*1.00"
  double level = 0.0;     // ln(comparison factor / reference factor)
  bool comparison_stronger = false;
};

enum class PsychometricShape { kCumulativeNormal, kWeibull };

struct ThresholdOptions {
  PsychometricShape shape = PsychometricShape::kCumulativeNormal;
  double max_lapse = 0.1;   // the lapse rate's upper bound, [0, 0.5)
  double criterion = 0.75;  // where on the lapse-free F the JND is read, (0.5, 1)
  double confidence = 0.95;
  int staircase_reversals = 6;                // k: the last k reversals are averaged (>= 2)
  std::vector<std::string> staircase_blocks;  // blocks taken as staircases whatever their moves
  bool per_participant = true;                // also fit each participant alone
  std::string validate() const;  // empty when usable, else the message naming the option
};

// The fitted curve at one level with its pointwise interval.
struct CurvePoint {
  double level = 0.0;  // ln ratio
  double p = 0.0;      // P(stronger | level)
  double low = 0.0, high = 0.0;
};

struct PsychometricFit {
  PsychometricShape shape = PsychometricShape::kCumulativeNormal;
  double pse = 0.0;     // ln ratio where F = 0.5
  double spread = 0.0;  // the scale of F on ln ratio
  double lapse = 0.0;
  double log_likelihood = 0.0;
  double weber_fraction = 0.0;  // exp(x_criterion - pse) - 1
  double ci_low = 0.0;          // profile-likelihood interval of the Weber fraction
  double ci_high = 0.0;         // +infinity when open above
  int trials = 0;
  bool converged = false;
  double max_lapse = 0.1;  // the lapse's bound in the fit
  bool pse_fitted = true;  // false: levels on one side, the PSE held at the reference
  // The covariance of (pse, ln spread, lapse logit) from the observed information at the
  // optimum; the rows of a parameter not fitted, or of a lapse at its bound, are 0.
  std::array<double, 9> covariance{};
  // The proportion P(stronger | x) the fit predicts.
  double probability(double level) const;
  // P(stronger | level) with its pointwise interval at `confidence`: the delta method on
  // logit P with `covariance`, back-transformed (inside 0..1).
  CurvePoint curve_point(double level, double confidence = 0.95) const;
};

struct StaircaseThreshold {
  std::string participant, block;
  int down_rule = 2;       // N of 1-up-N-down (the fewest "stronger" answers before a step down)
  double target = 0.0;     // 0.5^(1/N), the P(correct) the staircase tracks
  int reversals_used = 0;  // of reversals_total
  int reversals_total = 0;
  double weber_fraction = 0.0;         // exp(mean of the last k reversal levels) - 1
  double ci_low = 0.0, ci_high = 0.0;  // t interval over those reversals
  PsychometricFit fit;                 // the staircase's trials fitted alone
};

// One level's data, for plots.
struct LevelCount {
  double level = 0.0;  // ln ratio
  int trials = 0;
  int stronger = 0;
};

struct ParameterThresholds {
  std::string parameter, reference;
  PsychometricFit panel;  // every participant's trials pooled
  std::vector<std::pair<std::string, PsychometricFit>> participants;
  std::vector<StaircaseThreshold> staircases;
  std::vector<LevelCount> counts;  // pooled, by level ascending
  std::vector<CurvePoint> curve;   // the panel's curve and band, 101 levels across the data
};

struct ThresholdsResult {
  std::vector<ParameterThresholds> parameters;  // in order of first appearance
  double criterion = 0.75;
  // [{parameter, reference, participant ("panel" or an id), method, weber_fraction, ci_low,
  //   ci_high (null when open), criterion, interval, pse, spread, lapse, trials}] — the
  // analysis.json `jnd` section; staircases add block, reversals and down_rule.
  nlohmann::json to_json() const;
};

// Fits one set of trials (all of one parameter and reference). Throws std::invalid_argument
// with fewer than 3 trials or fewer than 2 distinct levels.
PsychometricFit fit_psychometric(std::span<const StrongerObservation> trials,
                                 const ThresholdOptions& options = {});

// The log-likelihood of the trials under the given parameters (for checks and grids).
double psychometric_log_likelihood(std::span<const StrongerObservation> trials,
                                   PsychometricShape shape, double pse, double spread,
                                   double lapse);

// The JND's Weber fraction for a spread (independent of the PSE).
double weber_fraction(PsychometricShape shape, double spread, double criterion);

// A staircase's threshold from its trials in order; nullopt when they do not look like one
// (see above) and `forced` is false, or when fewer than 2 reversals occurred.
std::optional<StaircaseThreshold> staircase_threshold(std::span<const StrongerObservation> trials,
                                                      const ThresholdOptions& options,
                                                      bool forced = false);

ThresholdsResult fit_thresholds(std::span<const StrongerObservation> trials,
                                const ThresholdOptions& options = {});

// The jnd rows of a trials table (question "stronger:PARAM"; first and second labelled
// "PARAM*FACTOR" or "PARAM"; answer 1 or 2, which felt stronger). Per participant and block,
// the reference is the label in every trial (of two such, the factor nearer 1). Refused with
// the row's line: a label of another parameter or with a factor that is not a positive
// number, an answer other than 1 or 2, a block where no label is in every trial.
std::vector<StrongerObservation> stronger_observations(const TrialsTable& table);

// The panel's psychometric curve with its data (analysis/svg_plot.h): the proportion
// "comparison felt stronger" per comparison level (measured) and the pooled fit
// (simulated), against the comparison / reference ratio; written whole or not at all.
std::string render_psychometric_plot(const ParameterThresholds& thresholds);
void write_psychometric_plot(const std::string& path, const ParameterThresholds& thresholds);

}  // namespace doorbench::study
