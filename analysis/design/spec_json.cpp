// spec.json (spec_report.h): the design, the felt quantities, the checks, the tolerance
// spreads, the perceptual tolerances and the alternatives as one JSON document;
// docs/design-spec.md describes each field.
#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "analysis/design/internal/spec_text.h"
#include "analysis/design/spec_report.h"
#include "core/json_number.h"

namespace doorbench {

namespace design_detail {

// The criterion of perceptual_tolerance.h in words.
std::string felt_criterion_text() {
  return "a door is felt as different in a quantity when |ln(q / q_nominal)| > ln(1 + w), w the "
         "quantity's JND as a Weber fraction at the 75 % point of the psychometric function "
         "(stronger by the factor 1 + w or weaker by 1 / (1 + w)); the share is over the Monte "
         "Carlo doors, with its Wilson 95 % interval";
}

}  // namespace design_detail

using design_detail::felt_criterion_text;

namespace {

using json = nlohmann::ordered_json;

// NaN and infinities become null (JSON has no NaN).
constexpr json (*number)(double) = &json_number<json>;

json felt_json(const FeltQuantities& felt) {
  json out = json::object();
  for (const FeltQuantityInfo& info : kFeltQuantities) {
    out[std::string(info.name)] = number(felt.*info.member);
  }
  out["unlatch_angle_rad"] = number(felt.unlatch_angle_rad);
  out["balance_angle_rad"] = number(felt.balance_angle_rad);
  return out;
}

json check_json(const FeelCheck& check) {
  json errors = json::array();
  for (const FeltQuantityError& e : check.errors) {
    errors.push_back({{"name", e.name},
                      {"model", number(e.model)},
                      {"recorded", number(e.recorded)},
                      {"error", number(e.error)},
                      {"error_percent", number(e.error_percent)}});
  }
  return {{"errors", errors},
          {"curve_rms_error_N", number(check.curve_rms_error_N)},
          {"opening_rms_error_N", number(check.opening_rms_error_N)},
          {"closing_rms_error_N", number(check.closing_rms_error_N)},
          {"bins_compared", check.bins_compared}};
}

json parameter_json(const DesignParameter& p) {
  return {{"name", p.name},
          {"unit", p.unit},
          {"free", p.free},
          {"as_is", number(p.as_is)},
          {"to_be", number(p.to_be)},
          {"change", number(p.change)},
          {"relative_change", number(p.relative_change)},
          {"uncertainty", number(p.uncertainty)},
          {"cost_of_change", number(p.weight)},
          {"bounds", {number(p.bounds.lower), number(p.bounds.upper)}},
          {"at_bound", p.at_bound},
          {"changed", p.changed}};
}
// spec.json's tolerances: those used (with their absolute band) and the spread per quantity.
json tolerances_json(const ToleranceResult& t) {
  json tolerances = json::array();
  for (std::size_t p = 0; p < t.tolerances.size(); ++p) {
    const ParameterTolerance& tol = t.tolerances[p];
    tolerances.push_back({{"name", tol.name},
                          {"plus_minus", tol.plus_minus},
                          {"percent", tol.percent},
                          {"distribution", std::string(to_string(tol.distribution))},
                          {"absolute", number(tol.absolute(t.nominal_values[p]))}});
  }
  json spreads = json::array();
  for (std::size_t q = 0; q < t.spreads.size(); ++q) {
    const QuantitySpread& s = t.spreads[q];
    json explained = json::object();
    for (std::size_t p = 0; p < t.tolerances.size(); ++p) {
      explained[t.tolerances[p].name] = number(t.explained[q][p]);
    }
    spreads.push_back({{"name", s.name},
                       {"nominal", number(s.nominal)},
                       {"mean", number(s.mean)},
                       {"sd", number(s.sd)},
                       {"p5", number(s.p5)},
                       {"p95", number(s.p95)},
                       {"min", number(s.min)},
                       {"max", number(s.max)},
                       {"count", s.count},
                       {"most_important", t.most_important[q]},
                       {"explained_variance", explained}});
  }
  return {{"samples", t.samples},     {"failed", t.failed},       {"threads", t.threads},
          {"elapsed_s", t.elapsed_s}, {"parameters", tolerances}, {"spreads", spreads}};
}

// An alternative's equivalence to the design (equivalent_solutions.h).
json equivalence_json(const SolutionEquivalence& q) {
  return {{"equivalent", q.equivalent},
          {"data_cost_difference", number(q.data_cost_difference)},
          {"same_data", q.same_data},
          {"same_feel", q.same_feel},
          {"felt_different", q.felt_different},
          {"parameters_differ", q.parameters_differ},
          {"tell_apart",
           {{"measurement", q.tell_apart.measurement},
            {"design_N", number(q.tell_apart.design_N)},
            {"alternative_N", number(q.tell_apart.alternative_N)},
            {"difference_N", number(q.tell_apart.difference_N)},
            {"resolvable", q.tell_apart.resolvable}}},
          {"verdict", q.verdict}};
}

json felt_misses_json(const std::vector<FeltMiss>& felt_misses) {
  json misses = json::array();
  for (const FeltMiss& miss : felt_misses) {
    misses.push_back({{"quantity", miss.quantity},
                      {"design", number(miss.design)},
                      {"tobe", number(miss.tobe)},
                      {"difference", number(miss.difference)},
                      {"jnds", number(miss.jnds)},
                      {"weber_fraction", number(miss.jnd.weber_fraction)},
                      {"jnd_source", miss.jnd.source}});
  }
  return misses;
}

json perceptual_row_json(const PerceptualRow& row) {
  return {{"doors", row.doors},
          {"felt_different", row.felt_different},
          {"share", number(row.share)},
          {"ci_low", number(row.ci_low)},
          {"ci_high", number(row.ci_high)},
          {"note", row.note}};
}

// spec.json's "perceptual": the panel's results and the perceptual tolerance table.
json perceptual_json(const PerceptualSpec& p) {
  json preference = json::array();
  for (const PanelPreference& v : p.preference) {
    preference.push_back({{"variant", v.variant},
                          {"worth", number(v.worth)},
                          {"ci_low", number(v.ci_low)},
                          {"ci_high", number(v.ci_high)}});
  }
  json thresholds = json::array();
  for (const PanelThreshold& t : p.thresholds) {
    thresholds.push_back({{"parameter", t.parameter},
                          {"reference", t.reference},
                          {"participant", t.participant},
                          {"method", t.method},
                          {"weber_fraction", number(t.weber_fraction)},
                          {"ci_low", number(t.ci_low)},
                          {"ci_high", number(t.ci_high)},
                          {"criterion", t.criterion}});
  }
  json quantities = json::array();
  for (std::size_t q = 0; q < p.rows.size(); ++q) {
    const PerceptualRow& row = p.rows[q];
    json entry = {{"quantity", row.quantity},
                  {"nominal", number(row.nominal)},
                  {"weber_fraction", number(row.jnd.weber_fraction)},
                  {"jnd_measured", row.jnd.measured},
                  {"jnd_source", row.jnd.source},
                  {"jnd_ci_low", number(row.jnd.ci_low)},
                  {"jnd_ci_high", number(row.jnd.ci_high)},
                  {"as_given", perceptual_row_json(row)}};
    if (q < p.proposal.rows.size()) entry["proposed"] = perceptual_row_json(p.proposal.rows[q]);
    quantities.push_back(entry);
  }
  json proposed = json::array();
  for (const ParameterTolerance& t : p.proposal.tolerances) {
    proposed.push_back({{"name", t.name},
                        {"plus_minus", number(t.plus_minus)},
                        {"percent", t.percent},
                        {"distribution", std::string(to_string(t.distribution))}});
  }
  return {{"campaign", p.campaign},
          {"tobe_source", p.tobe_source},
          {"notes", p.notes},
          {"criterion", felt_criterion_text()},
          {"preference_scale", preference},
          {"thresholds", thresholds},
          {"felt_share", number(p.proposal.felt_share)},
          {"quantities", quantities},
          {"proposal",
           {{"factor", number(p.proposal.factor)},
            {"reached", p.proposal.reached},
            {"summary", p.proposal.summary},
            {"over_factor", number(p.proposal.over_factor)},
            {"factors_tried", p.proposal.factors_tried},
            {"worst_shares", p.proposal.worst_shares},
            {"samples_run", p.proposal.samples_run},
            {"tolerances", proposed}}}};
}
}  // namespace

std::string spec_json(const InverseDesignResult& design, const SpecEvaluation& e) {
  if (design.solutions.empty())
    throw std::invalid_argument("spec: the inverse design has no solution");
  const DesignSolution& best = design.solutions.front();
  json root;
  root["about"] =
      "doorbench design specification: the physical door that feels like the TO-BE recordings "
      "with the smallest change to the AS-IS door (docs/design-spec.md)";
  root["command"] = e.command;
  root["asis_source"] = e.asis_source;
  root["tobe_sources"] = e.tobe_sources;
  root["warnings"] = e.warnings;
  root["interrupted"] = e.interrupted.empty() ? json(nullptr) : json(e.interrupted);
  root["feasible"] = design.feasible;
  root["infeasibility"] = design.infeasibility;
  // When infeasible: the binding parameters as the data ask for them (bounds widened).
  json requested = json::array();
  for (const DesignParameter& p : design.requested) requested.push_back(parameter_json(p));
  root["requested"] = requested;
  root["notes"] = design.notes;
  json parameters = json::array();
  for (const DesignParameter& p : best.parameters) parameters.push_back(parameter_json(p));
  root["parameters"] = parameters;
  root["fit"] = {{"window_rmse_rad_s", number(best.fit.window.rmse())},
                 {"rate_noise_rad_s", number(design.rate_noise_rad_s)},
                 {"misfit_factor", number(design.misfit_factor)},
                 {"commanded_torque", design.commanded_torque},
                 {"effective_regularization", number(design.effective_regularization)},
                 {"data_cost", number(best.data_cost)},
                 {"size_of_change", number(best.size_of_change)},
                 {"parts_changed_cost", number(best.parts_changed_cost)},
                 {"parts_changed", best.parts_changed},
                 {"held_at_as_is", best.held_at_as_is},
                 {"converged", best.converged}};
  // One definition; every model read along the TO-BE recordings' motion (the check's), the
  // standard run (virtual hand) beside it under its own stated conditions.
  root["felt"] = {{"definition", felt_definition(e.felt)},
                  {"conditions", "along the TO-BE recordings' motion"},
                  {"before", felt_json(e.check_before.model)},
                  {"after", felt_json(e.check_after.model)},
                  {"tobe_recorded", felt_json(e.check_after.recorded)},
                  {"standard_run",
                   {{"conditions", standard_run_conditions(e.felt)},
                    {"before", felt_json(e.felt_before)},
                    {"after", felt_json(e.felt_after)}}}};
  json steps = json::array();
  for (const SparseStep& step : design.sparse_steps) {
    json tried = json::array();
    for (const auto& [name, cost] : step.tried)
      tried.push_back({{"name", name}, {"data_cost", cost}});
    steps.push_back({{"added", step.added},
                     {"free", step.free},
                     {"data_cost", number(step.data_cost)},
                     {"reduced_data_cost", number(step.reduced_data_cost)},
                     {"window_rmse_rad_s", number(step.window_rmse_rad_s)},
                     {"tried", tried},
                     {"equivalent", step.equivalent}});
  }
  root["design_search"] = {
      {"steps", steps},
      {"stopped", design.sparse_stop},
      {"goal", design.felt_goal ? "every felt quantity within its JND" : "the data cost"},
      {"felt_misses", felt_misses_json(design.felt_misses)},
      {"parts_tried", design.parts_tried},
      {"every_part_free",
       design.every_part_fitted
           ? json{{"parts_changed", design.every_part_parts_changed},
                  {"felt_misses", felt_misses_json(design.every_part_felt_misses)}}
           : json(nullptr)}};
  root["check"] = {{"before", check_json(e.check_before)}, {"after", check_json(e.check_after)}};
  root["tolerances"] = e.tolerances ? tolerances_json(*e.tolerances) : json(nullptr);
  root["perceptual"] = e.perceptual ? perceptual_json(*e.perceptual) : json(nullptr);
  json alternatives = json::array();
  for (std::size_t s = 1; s < design.solutions.size(); ++s) {
    const DesignSolution& alt = design.solutions[s];
    json changes = json::array();
    for (const DesignParameter& p : alt.parameters) {
      if (p.free && p.changed) changes.push_back(parameter_json(p));
    }
    json entry = {{"index", s},
                  {"size_of_change", number(alt.size_of_change)},
                  {"parts_changed_cost", number(alt.parts_changed_cost)},
                  {"parts_changed", alt.parts_changed},
                  {"data_cost", number(alt.data_cost)},
                  {"window_rmse_rad_s", number(alt.fit.window.rmse())},
                  {"held_at_as_is", alt.held_at_as_is},
                  {"swapped", alt.swapped},
                  {"changes", changes}};
    if (s - 1 < e.felt_alternatives.size()) entry["felt"] = felt_json(e.felt_alternatives[s - 1]);
    if (s - 1 < e.equivalence.size()) entry["equivalence"] = equivalence_json(e.equivalence[s - 1]);
    alternatives.push_back(entry);
  }
  root["alternatives"] = alternatives;
  json equivalent = json::array();
  for (const SolutionEquivalence& q : e.equivalence) {
    if (q.equivalent) equivalent.push_back(q.solution + 1);
  }
  root["equivalence"] = {{"criterion", e.equivalence_criterion},
                         {"equivalent_alternatives", equivalent}};
  return root.dump(2) + "\n";
}

}  // namespace doorbench
