#include "analysis/design/equivalent_solutions.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/number_format.h"
#include "core/numbers.h"
#include "core/units.h"

namespace doorbench {

namespace {

double weber_fraction(const EquivalenceOptions& options, std::string_view quantity) {
  for (const FeltJnd& jnd : options.jnds) {
    if (jnd.quantity == quantity) return jnd.weber_fraction;
  }
  return typical_felt_jnd(quantity).weber_fraction;
}

// The free parameters whose values differ beyond both solutions' combined uncertainty and
// the share of their bound width, as "F0 41.6 vs 40 N" (design's value first).
std::vector<std::string> parameters_differ(const DesignSolution& design,
                                           const DesignSolution& alternative,
                                           const EquivalenceOptions& options) {
  std::vector<std::string> differ;
  for (const DesignParameter& a : alternative.parameters) {
    if (!a.free) continue;
    const auto d = std::find_if(design.parameters.begin(), design.parameters.end(),
                                [&](const DesignParameter& p) { return p.name == a.name; });
    if (d == design.parameters.end()) continue;
    const double difference = std::abs(a.to_be - d->to_be);
    double combined = 0.0;
    for (double u : {a.uncertainty, d->uncertainty}) {
      if (std::isfinite(u)) combined += u * u;
    }
    const double width = a.bounds.upper - a.bounds.lower;
    const double floor_share =
        std::isfinite(width) ? options.parameter_fraction_of_bounds * width : 0.0;
    if (difference > std::sqrt(combined) && difference > floor_share) {
      differ.push_back(
          printf_text("%s %.5g vs %.5g %s", a.name.c_str(), d->to_be, a.to_be, a.unit.c_str()));
    }
  }
  return differ;
}

// One hand-force measurement of both doors: per angle bin (and direction), the design's and
// the alternative's value.
struct Measured {
  std::string what;  // "hand force opening at %.0f deg (...)", %.0f the bin's angle
  std::vector<double> angle_rad, design_N, alternative_N;
};

// The force–angle curve's bins of both doors in one run, one Measured per direction.
void add_run(const DoorModel& design, const DoorModel& alternative, const FeltOptions& felt,
             const std::string& conditions, std::vector<Measured>& out) {
  const PreparedData run_d = virtual_hand_strokes(design, felt);
  const PreparedData run_a = virtual_hand_strokes(alternative, felt);
  const double theta_max = design.geometry().theta_max_rad;
  const ForceAngleCurve cd = force_angle_curve({&run_d, 1}, theta_max, felt);
  const ForceAngleCurve ca = force_angle_curve({&run_a, 1}, theta_max, felt);
  out.push_back({"hand force opening at %.0f deg (" + conditions + ")", cd.angle_rad,
                 cd.opening_force_N, ca.opening_force_N});
  out.push_back({"hand force closing at %.0f deg (" + conditions + ")", cd.angle_rad,
                 cd.closing_force_N, ca.closing_force_N});
}

// The force that holds each door still at the bins' angles: −τ(θ, 0) / r_h.
Measured holding_forces(const DoorModel& design, const DoorModel& alternative,
                        const FeltOptions& felt) {
  Measured m{"hand force holding the door still at %.0f deg", {}, {}, {}};
  const double theta_max = design.geometry().theta_max_rad;
  for (double theta = 0.5 * felt.bin_width_rad; theta < theta_max; theta += felt.bin_width_rad) {
    m.angle_rad.push_back(theta);
    m.design_N.push_back(-design.torque_Nm(theta, 0.0) / design.geometry().handle_radius_m);
    m.alternative_N.push_back(-alternative.torque_Nm(theta, 0.0) /
                              alternative.geometry().handle_radius_m);
  }
  return m;
}

TellApart tell_apart(const DoorModel& design, const DoorModel& alternative,
                     const EquivalenceOptions& options) {
  std::vector<Measured> measured;
  add_run(design, alternative, options.felt, standard_run_conditions(options.felt), measured);
  FeltOptions fast = options.felt;
  fast.hand.duration_s = options.felt.hand.duration_s / options.fast_factor;
  add_run(design, alternative, fast, standard_run_conditions(fast), measured);
  measured.push_back(holding_forces(design, alternative, options.felt));
  TellApart best{"", kNaN, kNaN, kNaN, false};
  for (const Measured& m : measured) {
    for (std::size_t b = 0; b < m.angle_rad.size(); ++b) {
      const double difference = m.alternative_N[b] - m.design_N[b];
      if (!std::isfinite(difference)) continue;
      if (std::isfinite(best.difference_N) && std::abs(difference) <= std::abs(best.difference_N)) {
        continue;
      }
      best.measurement = printf_text(m.what.c_str(), m.angle_rad[b] * kDegPerRad);
      best.design_N = m.design_N[b];
      best.alternative_N = m.alternative_N[b];
      best.difference_N = difference;
    }
  }
  best.resolvable =
      std::isfinite(best.difference_N) && std::abs(best.difference_N) > options.force_resolution_N;
  return best;
}

std::string joined(const std::vector<std::string>& items) {
  std::string text;
  for (const std::string& item : items) text += (text.empty() ? "" : ", ") + item;
  return text;
}

// The felt quantities' labels for people ("peak force to unlatch (N)") from their names.
std::vector<std::string> felt_labels(const std::vector<std::string>& names) {
  std::vector<std::string> labels;
  for (const std::string& name : names) {
    for (const FeltQuantityInfo& info : kFeltQuantities) {
      if (info.name == name) labels.push_back(felt_label(info));
    }
  }
  return labels;
}

std::string verdict(const SolutionEquivalence& e, const EquivalenceOptions& options) {
  std::string text = e.equivalent ? "equivalent to the design: " : "not equivalent: ";
  text += printf_text("data cost %+.1f %% (margin %.3g %%)", 100.0 * e.data_cost_difference,
                      100.0 * options.data_cost_margin);
  text += e.same_feel ? ", felt the same (every quantity within its JND)"
                      : ", felt as different in " + joined(felt_labels(e.felt_different));
  text += e.parameters_differ.empty()
              ? ", the same parameters"
              : ", different parts (design vs this one: " + joined(e.parameters_differ) + ")";
  const TellApart& t = e.tell_apart;
  if (!std::isfinite(t.difference_N)) return text + "; no hand-force measurement to compare";
  text += t.resolvable ? "; told apart by the "
                       : "; no hand-force measurement tells them apart "
                         "(largest difference: the ";
  text += printf_text("%s, %.2f N vs %.2f N", t.measurement.c_str(), t.design_N, t.alternative_N);
  if (!t.resolvable) {
    text += printf_text(", %.2g N, under the %.2g N resolution): only measuring the parts does",
                        std::abs(t.difference_N), options.force_resolution_N);
  }
  return text;
}

// Where the JNDs come from: "the typical published ones", or "the panel's measured ones for
// 2 quantities, the typical published ones for the rest".
std::string jnd_sources(const EquivalenceOptions& options) {
  std::size_t measured = 0;
  for (const FeltJnd& jnd : options.jnds) measured += jnd.measured ? 1 : 0;
  if (measured == 0) return "the typical published ones";
  return printf_text(
      "the panel's measured ones for %zu quantit%s, the typical published ones "
      "for the rest",
      measured, measured == 1 ? "y" : "ies");
}

}  // namespace

std::string EquivalenceOptions::validate() const {
  if (!(data_cost_margin >= 0.0) || !std::isfinite(data_cost_margin)) {
    return "equivalence: data_cost_margin must be >= 0";
  }
  if (!(parameter_fraction_of_bounds >= 0.0) || !std::isfinite(parameter_fraction_of_bounds)) {
    return "equivalence: parameter_fraction_of_bounds must be >= 0";
  }
  if (!(force_resolution_N > 0.0) || !std::isfinite(force_resolution_N)) {
    return "equivalence: force_resolution_N must be > 0";
  }
  if (!(fast_factor > 1.0) || !std::isfinite(fast_factor)) {
    return "equivalence: fast_factor must be > 1";
  }
  for (const FeltJnd& jnd : jnds) {
    if (!(jnd.weber_fraction > 0.0) || !std::isfinite(jnd.weber_fraction)) {
      return "equivalence: the JND of " + jnd.quantity + " must be a positive number";
    }
  }
  return felt.validate();
}

std::string equivalence_criterion(const EquivalenceOptions& options) {
  return printf_text(
      "an alternative is equivalent to the design when their data costs on the TO-BE "
      "recordings differ by at most %.3g %% of the smaller, no felt quantity of the standard "
      "run differs by more than its JND (%s), and some free parameter differs beyond both "
      "uncertainties and %.3g %% of its bound width; the measurement that tells them apart is "
      "the hand force (standard run, %.3g times faster, or holding still, per %.3g deg of "
      "angle) where they differ most, told apart when by more than %.3g N",
      100.0 * options.data_cost_margin, jnd_sources(options).c_str(),
      100.0 * options.parameter_fraction_of_bounds, options.fast_factor,
      options.felt.bin_width_rad * kDegPerRad, options.force_resolution_N);
}

std::vector<SolutionEquivalence> assess_equivalence(const InverseDesignResult& design,
                                                    const EquivalenceOptions& options) {
  if (std::string error = options.validate(); !error.empty()) throw std::invalid_argument(error);
  std::vector<SolutionEquivalence> out;
  if (design.solutions.size() < 2) return out;
  const DesignSolution& chosen = design.solutions.front();
  const FeltQuantities felt_chosen = felt_quantities(chosen.model, options.felt);
  for (std::size_t s = 1; s < design.solutions.size(); ++s) {
    const DesignSolution& alt = design.solutions[s];
    SolutionEquivalence e;
    e.solution = s;
    const double smaller = std::min(chosen.data_cost, alt.data_cost);
    e.data_cost_difference = smaller > 0.0 ? (alt.data_cost - chosen.data_cost) / smaller
                                           : (alt.data_cost == chosen.data_cost ? 0.0 : kNaN);
    e.same_data = std::abs(e.data_cost_difference) <= options.data_cost_margin;
    const FeltQuantities felt_alt = felt_quantities(alt.model, options.felt);
    for (const FeltQuantityInfo& info : kFeltQuantities) {
      const double nominal = felt_chosen.*info.member, value = felt_alt.*info.member;
      if (!std::isfinite(nominal) || !std::isfinite(value) || value == nominal) continue;
      if (felt_as_different(value, nominal, weber_fraction(options, info.name))) {
        e.felt_different.emplace_back(info.name);
      }
    }
    e.same_feel = e.felt_different.empty();
    e.parameters_differ = parameters_differ(chosen, alt, options);
    e.equivalent = e.same_data && e.same_feel && !e.parameters_differ.empty();
    e.tell_apart = tell_apart(chosen.model, alt.model, options);
    e.verdict = verdict(e, options);
    out.push_back(std::move(e));
  }
  return out;
}

}  // namespace doorbench
