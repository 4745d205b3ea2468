#pragma once
// The design specification: from the inverse design (inverse_design.h), the check of the
// TO-BE door against the TO-BE recordings and the tolerance analysis, a folder with
//   spec.json  machine-readable: per parameter AS-IS, TO-BE, change, uncertainty, unit; felt
//              quantities before/after; the check's errors; tolerance spreads; alternatives
//   spec.html  self-contained (tables, inline SVG plots)
//   spec.pdf   when weasyprint is installed (it renders the HTML), else left out
// docs/design-spec.md describes each field.
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "analysis/design/equivalent_solutions.h"
#include "analysis/design/felt_quantities.h"
#include "analysis/design/inverse_design.h"
#include "analysis/design/perceptual_tolerance.h"
#include "analysis/design/tolerance_analysis.h"

namespace doorbench {

// Everything measured about a design besides the inverse fit itself.
struct SpecEvaluation {
  std::string command;      // how the report was made (shown in it)
  std::string asis_source;  // the AS-IS parameter file
  std::vector<std::string> tobe_sources;
  // What the report warns of (each a sentence, without "warning: "): in spec.json's
  // "warnings", at the top of spec.html; the spec verb prints them on stderr too.
  std::vector<std::string> warnings;
  FeltQuantities felt_before{};                   // the AS-IS door, virtual hand
  FeltQuantities felt_after{};                    // the TO-BE door (first solution), virtual hand
  std::vector<FeltQuantities> felt_alternatives;  // the other solutions, virtual hand
  FeelCheck check_before;                         // AS-IS model against the TO-BE recordings
  FeelCheck check_after;                          // TO-BE model against them
  std::optional<ToleranceResult> tolerances;      // of the TO-BE door
  FeltOptions felt;  // the felt quantities' definition and the standard run used
  // `spec --campaign`: the panel's preference scale and thresholds, and the perceptual
  // tolerance table (perceptual_tolerance.h); shown beside the tolerances when present.
  std::optional<PerceptualSpec> perceptual;
  // Each alternative judged against the design (equivalent_solutions.h), in the solutions'
  // order, and the criterion as one sentence.
  std::vector<SolutionEquivalence> equivalence;
  std::string equivalence_criterion;
  // "" when every part ran; else when a stop request came and what it left out (e.g.
  // "during the tolerance Monte Carlo: no tolerance analysis"), also one of `warnings`.
  std::string interrupted;
};

struct SpecEvaluationOptions {
  FeltOptions felt;
  bool run_tolerances = true;
  ToleranceSpec tolerances;  // empty: default_tolerances(the TO-BE model)
  MonteCarloOptions monte_carlo;
  // Which alternatives are equivalent (its felt options are replaced by `felt`).
  EquivalenceOptions equivalence;
  std::string validate() const;
};

// Felt quantities before and after (and of each alternative), both checks and the tolerance
// Monte Carlo of the first solution. Throws std::invalid_argument when `design` holds no
// solution or `tobe` no strokes. A stop request (monte_carlo.stop_requested) during the
// Monte Carlo leaves the tolerances out (SpecEvaluation::interrupted).
SpecEvaluation evaluate_spec(const DoorModel& asis, const InverseDesignResult& design,
                             std::span<const PreparedData> tobe,
                             const SpecEvaluationOptions& options = {});

struct SpecReportFiles {
  std::filesystem::path json, html, pdf;  // pdf empty when none was made
  std::string pdf_note;                   // why not, or the renderer used
};

// spec.json's text (what write_spec_report writes).
std::string spec_json(const InverseDesignResult& design, const SpecEvaluation& evaluation);
// The summary `doorbench spec` prints: what to change (three lines), the felt quantities along
// the TO-BE recordings (AS-IS model, design, recorded) and in the standard run, each with its
// conditions.
std::string spec_summary(const InverseDesignResult& design, const SpecEvaluation& evaluation);
// spec.html's text.
std::string spec_html(const InverseDesignResult& design, const SpecEvaluation& evaluation);

// Writes the folder (created when missing). `pdf_renderer`: the program turning HTML into PDF
// ("" = look for weasyprint on PATH; "none" = no PDF; acquisition/session/pdf_output.h). A
// spec.pdf that this run does not render (not asked for, failed, stopped) is removed, so an
// earlier run's never stands beside this spec.html (output rule 5).
// Throws std::runtime_error naming the file it cannot write, and StopRequested when `stop`
// asked while the PDF was rendered (spec.json and spec.html are then written, the PDF not).
SpecReportFiles write_spec_report(const std::filesystem::path& dir,
                                  const InverseDesignResult& design,
                                  const SpecEvaluation& evaluation,
                                  const std::string& pdf_renderer = "", const StopHook& stop = {});

}  // namespace doorbench
