// Equivalent solutions of the inverse design (analysis/design/equivalent_solutions.h): two
// parameter sets that give the same door (a preload raised, or the spring's free length
// shortened by as much tension) are equivalent, and no hand force tells them apart; a
// softer catch spring instead of a lower catch preload is equivalent too, but a faster run
// tells them apart; a catch much softer is felt, and an alternative the recordings fit
// clearly worse is not equivalent either. The design results are made by hand, the doors and their
// feel are simulated.
#include <catch2/catch.hpp>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/design/equivalent_solutions.h"
#include "analysis/design/spec_report.h"
#include "analysis/model/parameter_file.h"
#include "analysis/simulation/fit_synthetic.h"

using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
using namespace doorbench;

namespace {

DoorModel with(const DoorModel& model, const char* name, double value) {
  std::vector<double> values(model.parameter_values().begin(), model.parameter_values().end());
  values.at(static_cast<std::size_t>(*model.find_parameter(name))) = value;
  return model.with_parameter_values(values);
}

double value_of(const DoorModel& model, const char* name) {
  return model.parameter_values()[static_cast<std::size_t>(*model.find_parameter(name))];
}

// A solution of `tobe` with every parameter but m_d free, uncertainties 0.1 % of the value.
DesignSolution solution_of(const DoorModel& asis, const DoorModel& tobe, double data_cost) {
  DesignSolution solution{.model = tobe,
                          .parameters = {},
                          .fit = {},
                          .held_at_as_is = {},
                          .at_bound = {},
                          .summary = {}};
  solution.data_cost = data_cost;
  for (int i = 0; i < tobe.parameter_count(); ++i) {
    DesignParameter p;
    p.name = tobe.parameter_name(i);
    p.unit = std::string(tobe.parameter_unit(i));
    p.free = p.name != "m_d";
    p.as_is = asis.parameter_values()[i];
    p.to_be = tobe.parameter_values()[i];
    p.change = p.to_be - p.as_is;
    p.relative_change = p.change / std::abs(p.as_is);
    p.uncertainty = p.free ? 0.001 * std::abs(p.to_be) : NAN;
    p.bounds = tobe.parameter_bounds()[i];
    p.changed = p.free && p.change != 0.0;
    solution.parts_changed += p.changed ? 1 : 0;
    solution.parameters.push_back(p);
  }
  return solution;
}

EquivalenceOptions fast_options() {
  EquivalenceOptions options;
  options.felt.hand.duration_s = 6.0;
  return options;
}

}  // namespace

TEST_CASE("equivalent solutions: the same spring tension by preload or by free length", "[spec]") {
  const DoorModel asis = reference_model(ModelKind::kPhysical);
  const double f0 = value_of(asis, "F0"), k_s = value_of(asis, "k_s"), l0 = value_of(asis, "L0");
  // T = F0 + k_s (L − L0): F0 + 4 % or L0 shorter by 0.04 F0 / k_s pull the same while the
  // spring is stretched beyond both free lengths (the whole range but the closed stop).
  const DoorModel preload = with(asis, "F0", 1.04 * f0);
  const DoorModel shorter = with(asis, "L0", l0 - 0.04 * f0 / k_s);
  InverseDesignResult design;
  design.solutions = {solution_of(asis, preload, 1000.0), solution_of(asis, shorter, 1010.0)};
  const std::vector<SolutionEquivalence> found = assess_equivalence(design, fast_options());
  REQUIRE(found.size() == 1);
  const SolutionEquivalence& q = found.front();
  INFO(q.verdict);
  CHECK(q.solution == 1);
  CHECK(q.data_cost_difference == Approx(0.01));
  CHECK(q.same_data);
  CHECK(q.same_feel);
  CHECK(q.felt_different.empty());
  REQUIRE(q.parameters_differ.size() == 2);
  CHECK_THAT(q.parameters_differ[0] + q.parameters_differ[1], Contains("L0") && Contains("F0"));
  CHECK(q.equivalent);
  CHECK_THAT(q.verdict, Contains("equivalent to the design: data cost +1.0 % (margin 5 %)"));
  // No hand force tells them apart (they are the same door where it moves).
  REQUIRE(std::isfinite(q.tell_apart.difference_N));
  CHECK(std::abs(q.tell_apart.difference_N) < 0.5);
  CHECK_FALSE(q.tell_apart.resolvable);
  CHECK_THAT(q.verdict, Contains("no hand-force measurement tells them apart"));
  CHECK_THAT(q.verdict, Contains("only measuring the parts does"));

  // The recordings fit the alternative 10 % worse: beyond the 5 % margin, not equivalent;
  // within a 20 % margin it is.
  design.solutions[1].data_cost = 1100.0;
  const SolutionEquivalence worse = assess_equivalence(design, fast_options()).front();
  CHECK_FALSE(worse.same_data);
  CHECK_FALSE(worse.equivalent);
  CHECK_THAT(worse.verdict, Contains("not equivalent: data cost +10.0 % (margin 5 %)"));
  EquivalenceOptions wide = fast_options();
  wide.data_cost_margin = 0.2;
  CHECK(assess_equivalence(design, wide).front().equivalent);
}

TEST_CASE("equivalent solutions: a catch's preload or its spring, and a catch much softer",
          "[spec]") {
  const DoorModel asis = reference_model(ModelKind::kPhysical);
  // The design lowers the catch's preload by 30 %, the alternative softens the catch spring
  // by 30 % instead; the recordings are made to fit both alike (the same data cost). The
  // standard run feels the same within every JND; a run three times faster tells them apart
  // at the catch (the spring's share of the force grows with the catch's travel).
  const DoorModel lower_preload = with(asis, "F_l0", 0.7 * value_of(asis, "F_l0"));
  InverseDesignResult design;
  design.solutions = {solution_of(asis, lower_preload, 500.0),
                      solution_of(asis, with(asis, "k_l", 0.7 * value_of(asis, "k_l")), 500.0),
                      solution_of(asis, with(asis, "k_l", 0.4 * value_of(asis, "k_l")), 500.0)};
  const std::vector<SolutionEquivalence> found = assess_equivalence(design, fast_options());
  REQUIRE(found.size() == 2);
  const SolutionEquivalence& spring = found[0];
  INFO(spring.verdict);
  CHECK(spring.same_data);
  CHECK(spring.same_feel);
  CHECK(spring.equivalent);
  CHECK(spring.tell_apart.resolvable);
  CHECK(std::abs(spring.tell_apart.difference_N) > 0.5);
  CHECK(spring.tell_apart.alternative_N - spring.tell_apart.design_N ==
        Approx(spring.tell_apart.difference_N));
  CHECK_THAT(spring.verdict, Contains("; told apart by the hand force"));

  // Softened by 60 %, the catch is felt: not equivalent, whatever the data cost says.
  const SolutionEquivalence& softer = found[1];
  INFO(softer.verdict);
  CHECK(softer.same_data);
  CHECK_FALSE(softer.same_feel);
  CHECK_FALSE(softer.equivalent);
  CHECK_THAT(softer.verdict, StartsWith("not equivalent: data cost +0.0 %"));
  bool peak = false;
  for (const std::string& name : softer.felt_different) peak = peak || name.rfind("peak_", 0) == 0;
  CHECK(peak);
  CHECK_THAT(softer.verdict, Contains("felt as different in peak force to unlatch (N)"));
  CHECK(softer.tell_apart.resolvable);
}

TEST_CASE("equivalent solutions: marked in spec.json and in the summary", "[spec]") {
  const DoorModel asis = reference_model(ModelKind::kPhysical);
  const double f0 = value_of(asis, "F0"), k_s = value_of(asis, "k_s"), l0 = value_of(asis, "L0");
  const DoorModel preload = with(asis, "F0", 1.04 * f0);
  InverseDesignResult design;
  design.solutions = {solution_of(asis, preload, 1000.0),
                      solution_of(asis, with(asis, "L0", l0 - 0.04 * f0 / k_s), 1010.0),
                      solution_of(asis, with(asis, "k_l", 0.4 * value_of(asis, "k_l")), 1000.0)};
  SyntheticStrokeOptions synthetic;
  synthetic.runs = {{1.0, 4.0}};
  const std::vector<PreparedData> recordings = {synthetic_strokes(preload, synthetic)};
  SpecEvaluationOptions options;
  options.felt.hand.duration_s = 6.0;
  options.run_tolerances = false;
  const SpecEvaluation e = evaluate_spec(asis, design, recordings, options);
  REQUIRE(e.equivalence.size() == 2);
  const nlohmann::json spec = nlohmann::json::parse(spec_json(design, e));
  CHECK(spec["equivalence"]["equivalent_alternatives"] == nlohmann::json::array({2}));
  CHECK_THAT(spec["equivalence"]["criterion"].get<std::string>(),
             Contains("differ by at most 5 % of the smaller"));
  const auto& second = spec["alternatives"][0]["equivalence"];
  CHECK(second["equivalent"] == true);
  CHECK(second["same_data"] == true);
  CHECK(second["tell_apart"]["resolvable"] == false);
  CHECK(second["verdict"] == e.equivalence[0].verdict);
  const auto& third = spec["alternatives"][1]["equivalence"];
  CHECK(third["equivalent"] == false);
  CHECK(third["same_feel"] == false);
  CHECK(third["tell_apart"]["resolvable"] == true);
  CHECK_THAT(third["tell_apart"]["measurement"].get<std::string>(), StartsWith("hand force "));
  const std::string summary = spec_summary(design, e);
  CHECK_THAT(summary, Contains("\n  #2 equivalent to the design: data cost +1.0 %"));
  CHECK_THAT(summary, Contains("\n  #3 not equivalent: data cost +0.0 %"));
  CHECK_THAT(spec_html(design, e), Contains("<b>equivalent</b>: equivalent to the design"));
}

TEST_CASE("equivalent solutions: options are checked", "[spec]") {
  EquivalenceOptions options;
  options.data_cost_margin = -0.1;
  CHECK(options.validate() == "equivalence: data_cost_margin must be >= 0");
  options = {};
  options.force_resolution_N = 0.0;
  CHECK(options.validate() == "equivalence: force_resolution_N must be > 0");
  options = {};
  options.fast_factor = 1.0;
  CHECK(options.validate() == "equivalence: fast_factor must be > 1");
  options = {};
  options.jnds = {FeltJnd{"friction_open_N", 0.0, false, NAN, NAN, "typical"}};
  CHECK(options.validate() == "equivalence: the JND of friction_open_N must be a positive number");
  options.jnds.clear();
  CHECK(options.validate().empty());
  InverseDesignResult one;
  CHECK(assess_equivalence(one).empty());
  options.data_cost_margin = NAN;
  CHECK_THROWS_WITH(assess_equivalence(one, options), "equivalence: data_cost_margin must be >= 0");
}
