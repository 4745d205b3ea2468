#pragma once
// Thurstonian discrimination statistics of a panel (docs/campaign.md, "Preference
// statistics"):
//
// identify-real (2-AFC): which of the two presentations was the real door. Proportion
// correct Pc = correct / n and d' = √2·Φ⁻¹(Pc) (Macmillan & Creelman, 2-AFC without bias);
// the 95 % interval is the Clopper–Pearson interval of Pc carried through the same
// (monotone) transform; p is the exact two-sided binomial test of Pc = 1/2
// (study/statistics/binomial.h). Per participant and for the panel (all trials pooled, which
// assumes the participants share one Pc; the per-participant rows show whether they do).
//
// Equivalence (two one-sided tests, Schuirmann 1987) against a margin M on d': the data say
// the two are indistinguishable only when the whole reported interval lies inside (−M, M),
// which is the same as both one-sided tests (H0: d' ≥ M, H0: d' ≤ −M) rejecting at
// (1 − confidence) / 2; p_equivalence is the larger of their p-values (exact binomial for
// 2-AFC, the likelihood root for 2-AC). The verdict is one of: a difference found (the test
// of no difference rejects), equivalent (inside the margin), a difference found that is
// inside the margin, or inconclusive (neither: it names how large a d' the data cannot
// exclude). The default margin, d' = 1, is about the 2-AFC JND (75 % correct: d' = 0.95;
// docs/campaign.md says why).
//
// 2-AC (preference-2ac): per pair of variants A, B (A the one first in the table), the
// counts prefer A, no preference, prefer B, whatever the presentation order. The
// Thurstonian 2-AC model (Christensen, Lee & Brockhoff 2012): the difference of the two
// sensations is N(d', 2) and the answer is A below −τ, B above τ, "no preference" between,
// so with γ₁ = P(prefer A), γ₂ = P(prefer A or none):
//   z_k = √2·Φ⁻¹(γ_k),  τ = (z₂ − z₁)/2,  d' = −(z₁ + z₂)/2
// (d' > 0: B preferred, sensR's sign). The interval for d' is the profile-likelihood
// (likelihood-root) interval, as sensR's twoAC reports it; standard errors from the
// observed information. A pair where nobody preferred A (or B) has an infinite d': its
// interval is then open on that side, the other end the profile's (the likelihood's supremum
// in place of its maximum); JSON null for the infinite values, with a note.
//
// Errors: TrialsTableError naming the line of an answer that does not belong to the
// question, or an identify-real trial without the real door.
// Thread safety: free functions without shared state.
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "study/trials_table.h"

namespace doorbench::study {

// The default equivalence margin on d' (--equivalence-dprime).
inline constexpr double kDefaultEquivalenceDprime = 1.0;

// What a discrimination test's data say (the verdict's kind; analysis.json "conclusion").
enum class Conclusion { kDifferent, kEquivalent, kDifferentWithinMargin, kInconclusive };
// "different", "equivalent", "different, within the margin", "inconclusive".
const char* conclusion_name(Conclusion conclusion);

struct Forced2Result {
  std::string participant;  // empty for the panel
  int n = 0, correct = 0;
  double pc = 0;
  double dprime = 0;               // ±infinity at Pc = 1 or 0
  double ci_low = 0, ci_high = 0;  // of d'
  double pc_low = 0, pc_high = 0;  // Clopper–Pearson interval of Pc
  double p = 1;                    // exact two-sided binomial test of Pc = 1/2
  double p_equivalence = 1;        // two one-sided exact binomial tests against d' = ±margin
};

// Pc, d', intervals and tests from counts. `confidence` in (0.5, 1), `margin` > 0.
Forced2Result forced_choice_2afc(int correct, int n, double confidence = 0.95,
                                 double margin = kDefaultEquivalenceDprime);

struct IdentifyReal {
  Forced2Result panel;
  std::vector<Forced2Result> participants;  // in order of first appearance
  double margin = kDefaultEquivalenceDprime;
  Conclusion conclusion = Conclusion::kInconclusive;
  std::string verdict;  // one sentence (docs/campaign.md has each, word for word)
};

// The panel's verdict from its counts (identify_real's).
IdentifyReal identify_verdict(IdentifyReal result, double confidence);

// The identify-real trials; `real_variant` names the real door in `first`/`second`.
// nullopt when the table has none.
std::optional<IdentifyReal> identify_real(const TrialsTable& table,
                                          const std::string& real_variant = "real",
                                          double confidence = 0.95,
                                          double margin = kDefaultEquivalenceDprime);

struct TwoAcResult {
  std::string first, second;  // A and B
  int prefer_first = 0, no_preference = 0, prefer_second = 0;
  double tau = 0, dprime = 0;        // NaN / ±infinity where not estimable
  double se_tau = 0, se_dprime = 0;  // NaN where the information is singular
  double ci_low = 0, ci_high = 0;    // profile likelihood interval of d'
  double p = 1;                      // likelihood-root test of d' = 0, two-sided
  double p_equivalence = 1;          // two one-sided likelihood-root tests against ±margin
  double margin = kDefaultEquivalenceDprime;
  Conclusion conclusion = Conclusion::kInconclusive;
  std::string verdict;  // one sentence naming the variants
  std::string note;     // why an estimate or interval is missing or at a bound
};

// From counts (prefer A, none, prefer B); the verdict names A and B as `first`, `second`.
TwoAcResult two_ac(int prefer_first, int no_preference, int prefer_second, double confidence = 0.95,
                   double margin = kDefaultEquivalenceDprime, const std::string& first = "A",
                   const std::string& second = "B");

// Every pair of the preference-2ac trials, in order of the pair's first appearance.
std::vector<TwoAcResult> two_ac_pairs(const TrialsTable& table, double confidence = 0.95,
                                      double margin = kDefaultEquivalenceDprime);

// The JSON sections (docs/campaign.md): `identify_real: {panel: {n, correct, pc, dprime,
// ci_low, ci_high, p, p_equivalence}, participants: [...], equivalence_margin, conclusion,
// verdict}` and `two_ac: [{first, second, tau, dprime, ci_low, ci_high, p, p_equivalence,
// equivalence_margin, conclusion, verdict, note, ...}]`. Non-finite numbers are null.
nlohmann::json identify_real_json(const IdentifyReal& result);
nlohmann::json two_ac_json(const std::vector<TwoAcResult>& results);

}  // namespace doorbench::study
