#pragma once
// Which of the inverse design's solutions are equivalent to the chosen design, and which
// measurement would tell each from it (docs/design-spec.md, "Equivalent solutions").
//
// The inverse design keeps several parameter sets that fit the TO-BE recordings about
// equally well (inverse_design.h). An alternative is *equivalent* to the design (the first
// solution) when all three hold:
//   - the same data: their data costs (½ Σ r² over the TO-BE recordings) differ by at most
//     `data_cost_margin` of the smaller one (the recordings cannot tell them apart);
//   - the same feel: in the standard run (felt_quantities.h) no felt quantity of the
//     alternative is felt as different from the design's (perceptual_tolerance.h's
//     felt_as_different, each quantity's JND: the panel's when given, else the typical one);
//   - different parts: some free parameter differs by more than both solutions' combined
//     standard uncertainty and `parameter_fraction_of_bounds` of its bound width.
// Then the choice between them is the engineer's (cost, supply), not the data's.
//
// Which measurement tells them apart: of the hand forces the two doors need — along the
// standard run (virtual hand) per angle bin and direction, along a run `fast_factor` times
// faster, and holding the door still (−τ(θ, 0) / r_h) at each bin's angle — the one where
// they differ most. It is `resolvable` when that difference exceeds `force_resolution_N`;
// otherwise no hand-force measurement separates them and only the parts themselves can.
//
// Errors: std::invalid_argument for options that validate() refuses. Thread safety: pure
// functions (each call simulates its own runs); models may be shared.
#include <cstddef>
#include <string>
#include <vector>

#include "analysis/design/felt_quantities.h"
#include "analysis/design/inverse_design.h"
#include "analysis/design/perceptual_tolerance.h"

namespace doorbench {

struct EquivalenceOptions {
  // The margin on the data cost (fraction of the smaller one), ≥ 0; the inverse design's
  // own equivalent_cost_tolerance by default.
  double data_cost_margin = InverseDesignOptions{}.equivalent_cost_tolerance;
  // JNDs per felt quantity (each named at most once); a quantity not named takes
  // typical_felt_jnd's.
  std::vector<FeltJnd> jnds;
  // A parameter differs when the change is beyond this share of its bound width too. ≥ 0.
  double parameter_fraction_of_bounds = 0.005;
  // A hand-force measurement tells two doors apart when they differ by more than this (N):
  // about a bench load cell's noise. > 0.
  double force_resolution_N = 0.5;
  // The fast run: the standard run's duration divided by this. > 1.
  double fast_factor = 3.0;
  FeltOptions felt;              // the standard run and the felt quantities' definition
  std::string validate() const;  // empty when usable, else the message naming the option
};

// The measurement that tells an alternative from the design.
struct TellApart {
  // "hand force closing at 3 deg (virtual hand, 0 to 80 deg and back in 10 s)", or
  // "hand force holding the door still at 41 deg".
  std::string measurement;
  double design_N = 0.0, alternative_N = 0.0;  // NaN when no measurement could be compared
  double difference_N = 0.0;                   // alternative − design
  bool resolvable = false;                     // |difference| > force_resolution_N
};

struct SolutionEquivalence {
  std::size_t solution = 0;  // its index in InverseDesignResult::solutions (≥ 1)
  // (alternative − design) / the smaller of the two data costs (NaN when both are 0).
  double data_cost_difference = 0.0;
  bool same_data = false;
  // Felt quantities (kFeltQuantities names) felt as different in the standard run.
  std::vector<std::string> felt_different;
  bool same_feel = false;
  // Free parameters whose values differ (the criterion above), as "F0 41.6 vs 40 N".
  std::vector<std::string> parameters_differ;
  bool equivalent = false;  // same_data && same_feel && parameters differ
  TellApart tell_apart;
  // One sentence: "equivalent to the design: ..." or "not equivalent: ...".
  std::string verdict;
};

// The criterion as one sentence, with the options' numbers (for reports).
std::string equivalence_criterion(const EquivalenceOptions& options);

// One entry per alternative (solutions 1, 2, ...), in order; empty with fewer than two
// solutions.
std::vector<SolutionEquivalence> assess_equivalence(const InverseDesignResult& design,
                                                    const EquivalenceOptions& options = {});

}  // namespace doorbench
