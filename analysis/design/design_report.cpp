// The inverse design's reports: InverseDesignResult::brief_report() and full_report() with
// their tables (parameters, solutions, the sparse search's sequence).
#include <cmath>
#include <string>

#include "analysis/design/inverse_design.h"
#include "core/number_format.h"

namespace doorbench {

namespace {

std::string parameter_table(const DesignSolution& solution, bool changed_only) {
  std::string text =
      "    parameter        AS-IS          TO-BE          change     rel      +-          w\n";
  for (const DesignParameter& p : solution.parameters) {
    if (changed_only && !p.changed) continue;
    text += printf_text(
        "    %-12s %12.5g %14.5g %14.4g %6s %11.3g %6.3g%s%s\n", p.name.c_str(), p.as_is, p.to_be,
        p.change,
        std::isfinite(p.relative_change) ? printf_text("%+.0f%%", 100 * p.relative_change).c_str()
                                         : "",
        p.uncertainty, p.weight, p.free ? "" : "  not free", p.at_bound ? "  AT BOUND" : "");
  }
  return text;
}

std::string solution_header(const DesignSolution& solution, int rank) {
  std::string origin = printf_text("start %d", solution.start_index);
  if (solution.start_index == DesignSolution::kSparseSearch) origin = "sparse design search";
  if (!solution.swapped.empty()) origin = "sparse design, " + solution.swapped;
  if (!solution.held_at_as_is.empty()) {
    origin = "fewest changes, AS-IS kept for";
    for (const std::string& name : solution.held_at_as_is) origin += " " + name;
  }
  return printf_text(
      "Solution %d (%s): parts changed %d (cost %.4g), size of change %.4g; window RMSE of omega "
      "%.4g rad/s, FIT %.1f%%; data cost %.4g, prior cost %.4g%s\n",
      rank, origin.c_str(), solution.parts_changed, solution.parts_changed_cost,
      solution.size_of_change, solution.fit.window.rmse(), solution.fit.window.fit_percent(),
      solution.data_cost, solution.prior_cost, solution.converged ? "" : " (not converged)");
}

std::string sparse_table(const InverseDesignResult& result) {
  if (result.sparse_steps.empty()) return "";
  std::string text = "Sparse design search (parts freed one at a time from AS-IS):\n";
  text += "    parts  added        data cost    phi      RMSE omega   also tried (data cost)\n";
  for (std::size_t s = 0; s < result.sparse_steps.size(); ++s) {
    const SparseStep& step = result.sparse_steps[s];
    std::string tried;
    for (const auto& [name, cost] : step.tried) {
      if (name == step.added) continue;
      const bool same =
          std::find(step.equivalent.begin(), step.equivalent.end(), name) != step.equivalent.end();
      tried += printf_text(" %s %.6g%s", name.c_str(), cost, same ? " (equivalent)" : "");
    }
    text += printf_text("    %5zu  %-12s %-12.6g %-8.4g %-12.4g%s\n", s,
                        s == 0 ? "(AS-IS)" : step.added.c_str(), step.data_cost,
                        step.reduced_data_cost, step.window_rmse_rad_s, tried.c_str());
  }
  return text + "    " + result.sparse_stop + "\n";
}

// How far the fit with every part free stays from the TO-BE in `quantity`:
// "; with every part free (9 parts changed) 12.1 JNDs", "...) within its JND", or empty when
// that fit was not made.
std::string every_part_miss(const InverseDesignResult& result, const std::string& quantity) {
  if (!result.every_part_fitted) return "";
  const std::string head =
      printf_text("; with every part free (%d parts changed) ", result.every_part_parts_changed);
  for (const FeltMiss& miss : result.every_part_felt_misses) {
    if (miss.quantity != quantity) continue;
    return head + (std::isfinite(miss.jnds) ? format_significant(miss.jnds, 3) + " JNDs"
                                            : std::string("the sign differs"));
  }
  return head + "within its JND";
}

}  // namespace

std::vector<std::string> InverseDesignResult::felt_miss_warnings() const {
  std::vector<std::string> warnings;
  std::string tried;
  for (const std::string& part : parts_tried) tried += (tried.empty() ? "" : ", ") + part;
  for (const FeltMiss& miss : felt_misses) {
    std::string label = miss.quantity;
    for (const FeltQuantityInfo& info : kFeltQuantities) {
      if (info.name == miss.quantity) label = felt_label(info);
    }
    warnings.push_back("the design does not feel like the TO-BE: its " + label + " is " +
                       format_significant(miss.design, 3) + " against the TO-BE's " +
                       format_significant(miss.tobe, 3) + " (" +
                       printf_text("%+.3g", miss.difference) + ", " +
                       (std::isfinite(miss.jnds) ? format_significant(miss.jnds, 3) + " JNDs"
                                                 : std::string("the sign differs")) +
                       "; JND " + format_significant(100 * miss.jnd.weber_fraction, 3) + " %, " +
                       miss.jnd.source + "); the sparse search tried " +
                       (tried.empty() ? "no part" : tried) + every_part_miss(*this, miss.quantity));
  }
  return warnings;
}

std::string InverseDesignResult::brief_report() const {
  std::string text = feasible ? "Inverse design: feasible" : "Inverse design: INFEASIBLE";
  text += printf_text(", %zu distinct solution(s) from %d start(s), %.1f s.\n", solutions.size(),
                      starts_run, total_time_s);
  if (!feasible) text += std::string("  ").append(infeasibility).append("\n");
  if (!solutions.empty()) {
    text += solution_header(solutions.front(), 1);
    text += parameter_table(solutions.front(), /*changed_only=*/true);
  }
  text += sparse_table(*this);
  return text;
}

std::string InverseDesignResult::full_report() const {
  std::string text = brief_report();
  text += printf_text(
      "TO-BE rate noise: %.4g rad/s; misfit factor phi %.4g; effective regularization %.4g\n",
      rate_noise_rad_s, misfit_factor, effective_regularization);
  for (std::size_t s = 0; s < solutions.size(); ++s) {
    text += std::string("\n").append(solution_header(solutions[s], static_cast<int>(s + 1)));
    text += parameter_table(solutions[s], /*changed_only=*/false);
    for (const std::string& note : solutions[s].summary.notes)
      text += std::string("    note: ").append(note).append("\n");
  }
  for (const std::string& note : notes) text += std::string("Note: ").append(note).append("\n");
  return text;
}

}  // namespace doorbench
