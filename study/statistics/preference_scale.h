#pragma once
// The panel's preference scale from paired comparisons (docs/campaign.md, "Preference
// statistics"): Bradley–Terry worths with Davidson's ties and a presentation-order effect,
// fitted by maximum likelihood (Newton–Raphson on the log-likelihood, which is concave in
// the parameters below), with 95 % intervals and the probability that each variant is the
// panel's favourite.
//
// The model, for a trial that presents variant i first and variant j second:
//   P(first preferred)  = π_i·e^δ / D
//   P(second preferred) = π_j / D
//   P(same)             = ν·sqrt(π_i·e^δ·π_j) / D,   D the sum of the three numerators,
// with worths λ = log π (the reference variant at λ = 0), δ the first-position advantage
// (log scale; 0 = no order effect) and ν ≥ 0 Davidson's tie parameter. Without any `same`
// answer the tie term is left out (ν = 0, Bradley & Terry's model); without a pair presented
// in both orders the order term is left out (δ = 0, it cannot be told from the worths).
//
// Intervals: Wald from the observed information (the model's, which assumes that every
// participant shares the same worths); when the panel has at least
// `min_bootstrap_participants` participants, the participants are also resampled with
// replacement (a participant-clustered bootstrap, which keeps each person's answers
// together and so carries the participants' disagreement into the interval), and the
// reported interval is estimate ± z·max(Wald SE, bootstrap SE), the bootstrap SE being half
// the central 68.27 % range of the replicates (robust to the few replicates where a variant
// never loses). Each estimate says which SE was used ("wald" or "bootstrap"). The worths, δ
// and log ν have symmetric intervals; ν's interval is exp of log ν's.
//
// Quasi-variances (Firth & de Menezes 2004; study/statistics/quasi_variance.h) of the worths,
// with three or more variants: one q per variant, the reference included, such that the
// variance of any difference of two worths is about q_i + q_j. They are fitted to the
// variances of the differences the reported intervals use: the Wald covariance's, or with the
// bootstrap the larger of the Wald variance and the bootstrap's (half the central 68.27 %
// range of the replicates' difference, squared), pair by pair. Each variant's comparison
// interval is worth ± z/√2 · sqrt(q): two variants whose comparison intervals do not overlap
// differ at about the 1 − confidence level (exactly so for equal quasi-variances; with
// unequal ones, non-overlap asks a little more).
//
// Errors: TrialsTableError (study/trials_table.h) naming the line of an answer that is not
// 1, 2 or same (same only in preference-2ac). PreferenceScaleError when the data cannot give
// a scale (fewer than two variants, a variant that never won or never lost: its worth is
// infinite; the message names it).
// Thread safety: free functions without shared state; `progress` is called on the caller's
// thread.
#include <cstdint>
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/stop_request.h"
#include "study/trials_table.h"

namespace doorbench::study {

class PreferenceScaleError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One answered paired-comparison trial.
struct PairTrial {
  int first = 0;        // index into PairData::variants
  int second = 0;       // index into PairData::variants
  int participant = 0;  // index into PairData::participants
  int answer = 0;       // 1: first preferred, 2: second preferred, 0: same
};

struct PairData {
  std::vector<std::string> variants;      // in order of first appearance in the table
  std::vector<std::string> participants;  // in order of first appearance
  std::vector<PairTrial> trials;
  bool has_ties() const;
  bool has_both_orders() const;  // some pair presented in both orders
};

// The rows whose question is `preference` or `preference-2ac` (answers 1, 2, and same for
// preference-2ac only). Throws TrialsTableError naming the line of another answer.
PairData pair_data(const TrialsTable& table);

struct PreferenceOptions {
  std::string reference;     // the variant at worth 0; empty: the first in the table
  bool order_effect = true;  // fit δ when some pair was presented in both orders
  int bootstrap_replicates = 1000;
  int min_bootstrap_participants = 6;
  std::uint64_t seed = 1;  // the bootstrap's and the favourite draws' generator
  double confidence = 0.95;
  // Asked before each bootstrap resample (core/stop_request.h): true throws StopRequested.
  StopHook stop_requested;
  std::string validate() const;  // empty when usable, else one line naming the option
};

// One estimate with its interval.
struct Estimate {
  double value = 0;
  double se_wald = 0;
  double se_bootstrap = 0;  // NaN when not bootstrapped
  double ci_low = 0, ci_high = 0;
  std::string interval;  // "wald", "bootstrap" or "reference" (fixed at 0)
};

struct VariantWorth {
  std::string variant;
  Estimate worth;             // log scale
  double quasi_variance = 0;  // NaN without quasi-variances (two variants, or no fit)
  double comparison_low = 0, comparison_high = 0;  // worth ∓ z/√2 · sqrt(quasi_variance)
  double p_favourite = 0;  // share of replicates (or draws) in which it has the top worth
  int wins = 0, losses = 0, ties = 0;  // its answers, whatever position
};

struct PreferenceScale {
  std::vector<VariantWorth> worths;  // in PairData's variant order
  std::optional<Estimate> order;     // δ, when fitted
  std::optional<Estimate> nu;        // ν (interval exp of log ν's), when there are ties
  double log_likelihood = 0;
  int iterations = 0;
  int trials = 0;
  int participants = 0;
  int replicates_used = 0;            // bootstrap replicates that converged (0: not bootstrapped)
  int replicates_failed = 0;          // where a variant never won or never lost
  std::string favourite_source;       // "bootstrap" or "normal draws from the Wald covariance"
  double quasi_variance_error = 0;    // the largest relative error of sqrt(q_i + q_j); NaN: none
  std::string quasi_variance_source;  // "wald" or "larger of wald and bootstrap, per pair"
  std::vector<std::string> notes;
};

// Fits the model and its intervals. `progress(done, total)` is called during the bootstrap.
// Throws PreferenceScaleError (see above) and std::invalid_argument for bad options.
PreferenceScale fit_preference_scale(const PairData& data, const PreferenceOptions& options = {},
                                     const std::function<void(int, int)>& progress = {});

// The point estimates alone (no intervals), exposed for the tests and the bootstrap: the
// parameters in the order worths of the non-reference variants, δ (when `order`), log ν (when
// `ties`). Returns nullopt when Newton does not converge (separated data).
struct PointFit {
  std::vector<double> worths;  // every variant, reference at 0
  double order = 0, log_nu = 0;
  std::vector<double> covariance;  // row-major over the free parameters
  int free_parameters = 0;
  double log_likelihood = 0;
  int iterations = 0;
};
std::optional<PointFit> fit_point(const PairData& data, int reference, bool order, bool ties);

// The JSON sections `preference_scale: [{variant, worth, ci_low, ci_high, quasi_variance,
// quasi_se, comparison_low, comparison_high, ...}]`,
// `ties: {nu, ci_low, ci_high}` and `order_effect: {delta, ci_low, ci_high}` (docs/campaign.md).
nlohmann::json preference_scale_json(const PreferenceScale& scale);

}  // namespace doorbench::study
