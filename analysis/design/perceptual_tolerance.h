#pragma once
// Tolerances judged by what people can feel (docs/design-spec.md, "The specification from the
// panel"): of the doors the tolerance Monte Carlo manufactures (tolerance_analysis.h), the
// share a panel member would feel as different from the nominal design in each felt
// quantity, and the common tightening (or loosening) of the tolerances that keeps every such
// share under a chosen level.
//
// The criterion: door s is felt as different in quantity q when
//     |ln(q_s / q_nominal)| > ln(1 + w)      (or q_s / q_nominal <= 0: the sign changed),
// w the quantity's just-noticeable difference as a Weber fraction read at the 75 % point of
// the psychometric function (thresholds on the log ratio, symmetric: stronger by the factor
// 1 + w or weaker by 1 / (1 + w)). The share is the fraction of the doors where q is defined,
// with the Wilson 95 % interval (binomial: the doors are independent draws).
//
// The JNDs come in as plain numbers (measured by a campaign's jnd blocks, or the typical
// published values of typical_felt_jnd): this file does not depend on study/.
// Errors: std::invalid_argument for bad options or a JND that is not a positive number.
// Thread safety: pure functions; propose_perceptual_tolerances runs tolerance_analysis on
// its own thread pool.
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/design/tolerance_analysis.h"

namespace doorbench {

// The JND of one felt quantity as a Weber fraction, and where it comes from.
struct FeltJnd {
  std::string quantity;                // a kFeltQuantities name, e.g. "friction_open_N"
  double weber_fraction = 0.0;         // > 0
  bool measured = false;               // from the panel; else a typical published value
  double ci_low = 0.0, ci_high = 0.0;  // the measurement's interval (NaN when typical or open)
  // "measured: k_l (panel, psychometric fit, pooled)" or "typical: stiffness 15%".
  std::string source;
};

// What a felt quantity is felt as, the typical published JND of that kind, and the model
// parameters whose measured JND stands for the quantity (the first one measured is used).
struct FeltJndKind {
  std::string_view quantity;
  std::string_view kind;  // "stiffness", "friction"
  double weber_fraction = 0.0;
  std::vector<std::string_view> parameters;
};
// One entry per kFeltQuantities entry, in its order (docs/design-spec.md has the table).
const std::vector<FeltJndKind>& felt_jnd_kinds();
// The typical JND of a quantity ("typical: friction 20%"). Throws std::invalid_argument for
// a name that is not a felt quantity.
FeltJnd typical_felt_jnd(std::string_view quantity);

// Wilson's score interval for a binomial proportion (successes of trials; z 1.96 for 95 %).
// {NaN, NaN} when trials is 0.
struct BinomialInterval {
  double low = 0.0, high = 0.0;
};
BinomialInterval wilson_interval(int successes, int trials, double z = 1.959963984540054);

// Is `value` felt as different from `nominal` with Weber fraction w (the criterion above)?
bool felt_as_different(double value, double nominal, double weber_fraction);

// One felt quantity's row of the perceptual tolerance table.
struct PerceptualRow {
  std::string quantity;
  double nominal = 0.0;
  FeltJnd jnd;
  int doors = 0;                       // Monte Carlo doors where the quantity is defined
  int felt_different = 0;              // of them, over the JND
  double share = 0.0;                  // felt_different / doors; NaN when not assessed
  double ci_low = 0.0, ci_high = 0.0;  // Wilson 95 %
  std::string note;                    // why not assessed (nominal 0 or undefined), else empty
};

// The table for a tolerance Monte Carlo. `jnds` names each quantity at most once; a quantity
// it does not name gets its typical JND. Throws std::invalid_argument for an unknown quantity
// or a Weber fraction that is not a positive finite number.
std::vector<PerceptualRow> perceptual_shares(const ToleranceResult& result,
                                             std::span<const FeltJnd> jnds);

// The largest share over the assessed rows (NaN when none is assessed).
double worst_share(std::span<const PerceptualRow> rows);

struct PerceptualToleranceOptions {
  double felt_share = 0.05;  // the level every share must stay under (at or below), (0, 1)
  // The common factor on every tolerance is searched in [min_factor, max_factor]: doubled
  // or halved from 1 until the worst share crosses the level, then bisected (in log2) until
  // the factor over the level is within factor_precision above the one under it, at most
  // bisection_steps times.
  double min_factor = 1.0 / 64.0;
  double max_factor = 4.0;
  int bisection_steps = 6;
  double factor_precision = 0.05;  // > 0
  // Each factor's Monte Carlo (but the given one) runs in batches of this many samples, the
  // same draws at every factor, and stops after the batch where every assessed share's 99 %
  // Wilson interval lies on one side of the level: wholly above it in one quantity, or at or
  // under it in all. Else it runs the Monte Carlo's every sample. 0: every sample at every
  // factor. >= 2 otherwise.
  int batch_samples = 100;
  // Called after each factor's Monte Carlo with the factor, its largest share and the
  // samples it ran (the caller's thread). Empty: none.
  std::function<void(double factor, double worst_share, int samples)> progress;
  std::string validate() const;  // empty when usable, else the message naming the option
};

struct PerceptualProposal {
  double felt_share = 0.0;
  double factor = 1.0;   // the largest factor tried whose worst share is at or under the level
  bool reached = false;  // false: even min_factor leaves a share over the level
  // The smallest factor tried above `factor` whose worst share is over the level (the
  // bracket's other end; the level is crossed between them); NaN when none was tried.
  double over_factor = 0.0;
  std::vector<ParameterTolerance> tolerances;       // proposed (as given × factor)
  std::vector<PerceptualRow> rows;                  // at the proposal (min_factor when not reached)
  std::vector<double> factors_tried, worst_shares;  // in the order run
  std::vector<int> samples_run;                     // per factor tried: the doors simulated
  std::string summary;                              // one sentence saying what was found
};

// Runs tolerance_analysis at scaled tolerances (the same seed and draws: common random
// numbers, so the worst share is a deterministic function of the factor and of the samples
// run) and returns the proposal. `given` is the Monte Carlo at factor 1 when already run
// (else it is run, in batches as the other factors).
PerceptualProposal propose_perceptual_tolerances(const DoorModel& design, const ToleranceSpec& spec,
                                                 const MonteCarloOptions& monte_carlo,
                                                 std::span<const FeltJnd> jnds,
                                                 const PerceptualToleranceOptions& options = {},
                                                 const ToleranceResult* given = nullptr);

// The panel's results shown beside the specification (read from a campaign's analysis.json
// by the app; plain numbers here).
struct PanelPreference {
  std::string variant;
  double worth = 0.0, ci_low = 0.0, ci_high = 0.0;
};
struct PanelThreshold {
  std::string parameter, reference, participant, method, criterion;
  double weber_fraction = 0.0, ci_low = 0.0, ci_high = 0.0;  // ci_high NaN when open
};

// Everything the report shows of the perceptual side.
struct PerceptualSpec {
  std::string campaign;     // the analysis.json read
  std::string tobe_source;  // which TO-BE feel was used, and why
  std::vector<std::string> notes;
  std::vector<PanelPreference> preference;
  std::vector<PanelThreshold> thresholds;
  std::vector<FeltJnd> jnds;        // one per felt quantity
  std::vector<PerceptualRow> rows;  // at the tolerances as given
  PerceptualProposal proposal;

  // The table as text for stdout: per quantity the JND, its source and the share felt as
  // different (as given and proposed), then the proposal's summary.
  std::string brief_report() const;
};

}  // namespace doorbench
