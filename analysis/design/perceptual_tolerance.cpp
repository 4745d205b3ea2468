#include "analysis/design/perceptual_tolerance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/number_format.h"
#include "core/numbers.h"

namespace doorbench {

namespace {

const FeltQuantityInfo* find_quantity(std::string_view name) {
  for (const FeltQuantityInfo& info : kFeltQuantities) {
    if (info.name == name) return &info;
  }
  return nullptr;
}

}  // namespace

const std::vector<FeltJndKind>& felt_jnd_kinds() {
  // The latch's peaks come from the catch's spring (the sensory model's k_inf and k_lock; the
  // perceptual controls latch_effort, the peak handle force to unlatch, and closing_effort,
  // analysis/model/perceptual_controls.h), the balance from the door's spring
  // (stiffness, 15 %: the low end of the published 15-20 %); the friction quantities are
  // felt as friction (20 %; the control smoothness is the dry friction felt at the handle).
  // docs/design-spec.md gives the sources.
  static const std::vector<FeltJndKind> kinds = {
      {"peak_unlatch_force_N", "stiffness", 0.15, {"k_l", "F_l0", "latch_effort", "k_inf"}},
      {"peak_latch_force_N", "stiffness", 0.15, {"k_l", "F_l0", "closing_effort", "k_lock"}},
      {"friction_near_closed_N",
       "friction",
       0.20,
       {"T_h", "mu_g", "mu_l", "b_h", "d1", "d2", "smoothness"}},
      {"friction_open_N",
       "friction",
       0.20,
       {"T_h", "mu_g", "mu_l", "b_h", "d1", "d2", "smoothness"}},
      {"free_movement_friction_N",
       "friction",
       0.20,
       {"T_h", "mu_g", "mu_l", "b_h", "d1", "d2", "smoothness"}},
      {"balance_force_N", "stiffness", 0.15, {"k_s", "F0", "k"}},
  };
  return kinds;
}

FeltJnd typical_felt_jnd(std::string_view quantity) {
  for (const FeltJndKind& kind : felt_jnd_kinds()) {
    if (kind.quantity != quantity) continue;
    FeltJnd jnd;
    jnd.quantity = std::string(quantity);
    jnd.weber_fraction = kind.weber_fraction;
    jnd.ci_low = jnd.ci_high = kNaN;
    jnd.source = "typical: " + std::string(kind.kind) + " " +
                 format_significant(100.0 * kind.weber_fraction, 3) + "%";
    return jnd;
  }
  throw std::invalid_argument("no felt quantity named " + std::string(quantity));
}

BinomialInterval wilson_interval(int successes, int trials, double z) {
  if (trials <= 0) return {kNaN, kNaN};
  const double n = trials;
  const double p = successes / n;
  const double z2 = z * z;
  const double centre = (p + z2 / (2 * n)) / (1 + z2 / n);
  const double half = z / (1 + z2 / n) * std::sqrt(p * (1 - p) / n + z2 / (4 * n * n));
  return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

bool felt_as_different(double value, double nominal, double weber_fraction) {
  const double ratio = value / nominal;
  if (!(ratio > 0)) return true;  // the sign changed (or the nominal is 0 and value is not)
  return std::abs(std::log(ratio)) > std::log1p(weber_fraction);
}

std::vector<PerceptualRow> perceptual_shares(const ToleranceResult& result,
                                             std::span<const FeltJnd> jnds) {
  for (const FeltJnd& jnd : jnds) {
    if (!find_quantity(jnd.quantity)) {
      throw std::invalid_argument("JND for " + jnd.quantity + ": no such felt quantity");
    }
    if (!(jnd.weber_fraction > 0) || !std::isfinite(jnd.weber_fraction)) {
      throw std::invalid_argument("JND for " + jnd.quantity +
                                  ": the Weber fraction must be a positive number");
    }
  }
  std::vector<PerceptualRow> rows;
  for (const FeltQuantityInfo& info : kFeltQuantities) {
    PerceptualRow row;
    row.quantity = std::string(info.name);
    row.nominal = result.nominal.*info.member;
    const auto given = std::find_if(jnds.begin(), jnds.end(),
                                    [&](const FeltJnd& j) { return j.quantity == info.name; });
    row.jnd = given != jnds.end() ? *given : typical_felt_jnd(info.name);
    for (const FeltQuantities& door : result.felt) {
      const double value = door.*info.member;
      if (!std::isfinite(value)) continue;
      ++row.doors;
      if (felt_as_different(value, row.nominal, row.jnd.weber_fraction)) ++row.felt_different;
    }
    if (!std::isfinite(row.nominal) || row.nominal == 0.0 || row.doors == 0) {
      row.share = row.ci_low = row.ci_high = kNaN;
      row.note = row.doors == 0 ? "no door defines it" : "the nominal value is 0 or undefined";
      row.felt_different = 0;
    } else {
      row.share = static_cast<double>(row.felt_different) / row.doors;
      const BinomialInterval interval = wilson_interval(row.felt_different, row.doors);
      row.ci_low = interval.low;
      row.ci_high = interval.high;
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

double worst_share(std::span<const PerceptualRow> rows) {
  double worst = kNaN;
  for (const PerceptualRow& row : rows) {
    if (std::isfinite(row.share) && !(row.share <= worst)) worst = row.share;
  }
  return worst;
}

std::string PerceptualToleranceOptions::validate() const {
  if (!(felt_share > 0 && felt_share < 1)) return "the felt share must be between 0 and 1";
  if (!(min_factor > 0 && min_factor <= 1)) return "min_factor must be in (0, 1]";
  if (!(max_factor >= 1) || !std::isfinite(max_factor)) return "max_factor must be >= 1";
  if (bisection_steps < 0) return "bisection_steps must be >= 0";
  if (!(factor_precision > 0) || !std::isfinite(factor_precision)) {
    return "factor_precision must be > 0";
  }
  if (batch_samples < 0 || batch_samples == 1) return "batch_samples must be 0 or >= 2";
  return "";
}

namespace {

ToleranceSpec scaled(const ToleranceSpec& spec, double factor) {
  ToleranceSpec result = spec;
  for (ParameterTolerance& t : result.parameters) t.plus_minus *= factor;
  return result;
}

struct Evaluation {
  double factor = 1.0;
  double worst = 0.0;
  int samples = 0;
  std::vector<PerceptualRow> rows;
  bool under(double level) const { return !(worst > level); }  // NaN (none assessed): under
};

// z of a two-sided 99 % interval: a factor's Monte Carlo stops early only on a clear answer.
constexpr double kDecisionZ = 2.5758293035489004;

// Is it clear on which side of `level` the worst share lies: some share's interval wholly
// above it, or every assessed share's at or under it?
bool decided(const std::vector<PerceptualRow>& rows, double level) {
  bool all_under = true;
  for (const PerceptualRow& row : rows) {
    if (!std::isfinite(row.share)) continue;
    const BinomialInterval interval = wilson_interval(row.felt_different, row.doors, kDecisionZ);
    if (interval.low > level) return true;
    if (!(interval.high <= level)) all_under = false;
  }
  return all_under;
}

// The shares at `factor`: the Monte Carlo in batches (options.batch_samples) of the same draws
// as every other factor's, until decided() or every sample is run.
Evaluation run_factor(const DoorModel& design, const ToleranceSpec& spec, double factor,
                      const MonteCarloOptions& monte_carlo, std::span<const FeltJnd> jnds,
                      const PerceptualToleranceOptions& options) {
  const ToleranceSpec tolerances = scaled(spec, factor);
  const int batch = options.batch_samples > 0 ? options.batch_samples : monte_carlo.samples;
  ToleranceResult all;
  Evaluation e;
  e.factor = factor;
  while (e.samples < monte_carlo.samples) {
    MonteCarloOptions part = monte_carlo;
    part.first_sample = monte_carlo.first_sample + e.samples;
    // A last batch of one sample is run with the one before (the analysis takes two or more).
    part.samples =
        monte_carlo.samples - e.samples < 2 * batch ? monte_carlo.samples - e.samples : batch;
    ToleranceResult result = tolerance_analysis(design, tolerances, part);
    if (e.samples == 0) all.nominal = result.nominal;
    all.felt.insert(all.felt.end(), result.felt.begin(), result.felt.end());
    e.samples += part.samples;
    e.rows = perceptual_shares(all, jnds);
    if (decided(e.rows, options.felt_share)) break;
  }
  e.worst = worst_share(e.rows);
  return e;
}

std::string samples_text(const PerceptualProposal& proposal, const MonteCarloOptions& mc,
                         const PerceptualToleranceOptions& options) {
  int all = 0;
  for (int n : proposal.samples_run) all += n;
  std::string text =
      "; a Monte Carlo of up to " + std::to_string(mc.samples) + " samples per factor";
  if (options.batch_samples > 0) {
    text += " in batches of " + std::to_string(options.batch_samples) +
            ", stopped where every share's 99% interval was clear of the level";
  }
  return text + " (" + std::to_string(all) + " samples, " +
         std::to_string(proposal.samples_run.size()) + " factors)";
}

}  // namespace

PerceptualProposal propose_perceptual_tolerances(const DoorModel& design, const ToleranceSpec& spec,
                                                 const MonteCarloOptions& monte_carlo,
                                                 std::span<const FeltJnd> jnds,
                                                 const PerceptualToleranceOptions& options,
                                                 const ToleranceResult* given) {
  if (std::string error = options.validate(); !error.empty()) throw std::invalid_argument(error);
  if (std::string error = monte_carlo.validate(); !error.empty()) {
    throw std::invalid_argument(error);
  }
  PerceptualProposal proposal;
  proposal.felt_share = options.felt_share;
  proposal.over_factor = kNaN;
  auto evaluate = [&](double factor) {
    Evaluation e;
    if (factor == 1.0 && given) {
      e.factor = factor;
      e.rows = perceptual_shares(*given, jnds);
      e.worst = worst_share(e.rows);
      e.samples = static_cast<int>(given->felt.size());
    } else {
      e = run_factor(design, spec, factor, monte_carlo, jnds, options);
    }
    proposal.factors_tried.push_back(factor);
    proposal.worst_shares.push_back(e.worst);
    proposal.samples_run.push_back(e.samples);
    if (options.progress) options.progress(factor, e.worst, e.samples);
    return e;
  };
  const double level = options.felt_share;
  Evaluation under = evaluate(1.0);
  Evaluation over;
  bool have_over = false;
  if (under.under(level)) {  // loosen while the share stays under
    while (under.factor * 2 <= options.max_factor * (1 + 1e-12)) {
      Evaluation next = evaluate(under.factor * 2);
      if (!next.under(level)) {
        over = std::move(next);
        have_over = true;
        break;
      }
      under = std::move(next);
    }
  } else {  // tighten until it falls under
    over = std::move(under);
    have_over = true;
    bool found = false;
    while (over.factor / 2 >= options.min_factor * (1 - 1e-12)) {
      Evaluation next = evaluate(over.factor / 2);
      if (next.under(level)) {
        under = std::move(next);
        found = true;
        break;
      }
      over = std::move(next);
    }
    if (!found) {
      proposal.factor = over.factor;
      proposal.reached = false;
      proposal.rows = over.rows;
      proposal.tolerances = scaled(spec, over.factor).parameters;
      proposal.summary = "even the tolerances × " + format_significant(over.factor, 3) +
                         " leave a share of " + format_significant(100 * over.worst, 3) +
                         "% felt as different (over " + format_significant(100 * level, 3) + "%)";
      return proposal;
    }
  }
  if (have_over) {
    for (int step = 0; step < options.bisection_steps &&
                       over.factor > under.factor * (1 + options.factor_precision);
         ++step) {
      Evaluation middle = evaluate(std::sqrt(under.factor * over.factor));
      if (middle.under(level)) {
        under = std::move(middle);
      } else {
        over = std::move(middle);
      }
    }
    proposal.over_factor = over.factor;
  }
  proposal.factor = under.factor;
  proposal.reached = true;
  proposal.rows = under.rows;
  proposal.tolerances = scaled(spec, under.factor).parameters;
  proposal.summary = "every tolerance × " + format_significant(under.factor, 3) +
                     " keeps each felt quantity's share felt as different at or under " +
                     format_significant(100 * level, 3) + "% (largest " +
                     format_significant(100 * under.worst, 3) + "%)";
  if (!have_over) {
    proposal.summary += "; the largest factor tried, " + format_significant(under.factor, 3);
  } else {
    proposal.summary += "; × " + format_significant(over.factor, 3) + " leaves " +
                        format_significant(100 * over.worst, 3) + "%";
  }
  proposal.summary += samples_text(proposal, monte_carlo, options);
  return proposal;
}

std::string PerceptualSpec::brief_report() const {
  // The source column as wide as its longest entry (a measured JND names its parameter).
  int width = 8;
  for (const PerceptualRow& row : rows) {
    width = std::max(width, static_cast<int>(row.jnd.source.size()));
  }
  std::string text = printf_text("  %-34s %6s  %-*s %s\n", "quantity (standard run)", "JND", width,
                                 "JND from", "felt as different: as given -> proposed");
  auto share = [](const PerceptualRow& row) {
    return std::isfinite(row.share) ? printf_text("%5.1f%% [%.1f, %.1f]", 100 * row.share,
                                                  100 * row.ci_low, 100 * row.ci_high)
                                    : std::string("  -  (") + row.note + ")";
  };
  for (std::size_t q = 0; q < rows.size(); ++q) {
    const PerceptualRow& row = rows[q];
    const std::string label = felt_label(kFeltQuantities[q]);
    text +=
        printf_text("  %-34s %5.1f%%  %-*s %s -> %s\n", label.c_str(), 100 * row.jnd.weber_fraction,
                    width, row.jnd.source.c_str(), share(row).c_str(),
                    q < proposal.rows.size() ? share(proposal.rows[q]).c_str() : "-");
  }
  return text + "  " + proposal.summary + "\n";
}

}  // namespace doorbench
