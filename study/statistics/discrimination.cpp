#include "study/statistics/discrimination.h"

#include <algorithm>
#include <boost/math/distributions/binomial.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/special_functions/beta.hpp>
#include <boost/math/tools/minima.hpp>
#include <boost/math/tools/roots.hpp>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "core/json_number.h"
#include "core/number_format.h"
#include "core/numbers.h"
#include "study/question.h"
#include "study/statistics/binomial.h"

namespace doorbench::study {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
const double kSqrt2 = std::sqrt(2.0);

double normal_quantile(double p) {
  if (p <= 0) return -kInf;
  if (p >= 1) return kInf;
  return boost::math::quantile(boost::math::normal(), p);
}

// Φ(x) and 1 − Φ(x), each accurate in its own tail.
double phi_lower(double x) {
  return 0.5 * std::erfc(-x / kSqrt2);
}
double phi_upper(double x) {
  return 0.5 * std::erfc(x / kSqrt2);
}

double z_for(double confidence) {
  return normal_quantile((1 + confidence) / 2);
}

// A d' in a verdict: 2 decimals.
std::string dprime_text(double value) {
  return format_fixed(value, 2);
}

// "95 %" for a confidence of 0.95.
std::string confidence_text(double confidence) {
  return format_significant(100 * confidence, 3) + " %";
}

// "d' 0.22 [-0.75, 1.20]", an open end written as inf.
std::string dprime_with_interval(double dprime, double low, double high) {
  return "d' " + dprime_text(dprime) + " [" + dprime_text(low) + ", " + dprime_text(high) + "]";
}

// The 2-AC log-likelihood of (τ, d') for counts n1, n2, n3.
double two_ac_log_likelihood(double tau, double d, double n1, double n2, double n3) {
  double ll = 0;
  const double lo = (-tau - d) / kSqrt2, hi = (tau - d) / kSqrt2;
  if (n1 > 0) ll += n1 * std::log(phi_lower(lo));
  if (n3 > 0) ll += n3 * std::log(phi_upper(hi));
  if (n2 > 0) {
    // The middle probability from the side where it is not a small difference of large
    // numbers.
    const double middle = hi <= 0 ? phi_lower(hi) - phi_lower(lo) : phi_upper(lo) - phi_upper(hi);
    ll += n2 * std::log(std::max(middle, 1e-300));
  }
  return ll;
}

// max over τ ≥ 0 of the log-likelihood at d'.
double profile_log_likelihood(double d, double n1, double n2, double n3) {
  if (n2 == 0) {
    // The likelihood falls with τ when nobody answered "no preference": τ = 0.
    return two_ac_log_likelihood(0, d, n1, n2, n3);
  }
  const auto minus = [&](double tau) { return -two_ac_log_likelihood(tau, d, n1, n2, n3); };
  const auto best = boost::math::tools::brent_find_minima(minus, 0.0, 10.0 + std::abs(d), 52);
  return -best.second;
}

}  // namespace

Forced2Result forced_choice_2afc(int correct, int n, double confidence, double margin) {
  if (n <= 0 || correct < 0 || correct > n)
    throw std::invalid_argument("2-AFC: need 0 <= correct <= n and n > 0");
  if (!(margin > 0) || !std::isfinite(margin))
    throw std::invalid_argument("2-AFC: the equivalence margin must be a positive d'");
  Forced2Result r;
  r.n = n;
  r.correct = correct;
  r.pc = double(correct) / n;
  r.dprime = kSqrt2 * normal_quantile(r.pc);
  const double alpha = 1 - confidence;
  r.pc_low = correct == 0 ? 0.0 : boost::math::ibeta_inv(correct, n - correct + 1, alpha / 2);
  r.pc_high = correct == n ? 1.0 : boost::math::ibeta_inv(correct + 1, n - correct, 1 - alpha / 2);
  r.ci_low = kSqrt2 * normal_quantile(r.pc_low);
  r.ci_high = kSqrt2 * normal_quantile(r.pc_high);
  r.p = binomial_two_sided_p(correct, n);
  // The two one-sided tests at Pc of d' = ±margin: H0 d' ≥ margin rejected by few correct
  // answers, H0 d' ≤ −margin by many.
  const double pc_margin = phi_lower(margin / kSqrt2);
  const double p_below = boost::math::cdf(boost::math::binomial(n, pc_margin), correct);
  const double p_above = correct == 0
                             ? 1.0
                             : boost::math::cdf(boost::math::complement(
                                   boost::math::binomial(n, 1.0 - pc_margin), correct - 1));
  r.p_equivalence = std::max(p_below, p_above);
  return r;
}

const char* conclusion_name(Conclusion conclusion) {
  switch (conclusion) {
    case Conclusion::kDifferent:
      return "different";
    case Conclusion::kEquivalent:
      return "equivalent";
    case Conclusion::kDifferentWithinMargin:
      return "different, within the margin";
    case Conclusion::kInconclusive:
      break;
  }
  return "inconclusive";
}

namespace {

// What the data say from the test of no difference (p) and the interval against the margin.
Conclusion conclude(double p, double low, double high, double margin, double confidence) {
  const bool within = low > -margin && high < margin;
  if (p < 1 - confidence)
    return within ? Conclusion::kDifferentWithinMargin : Conclusion::kDifferent;
  return within ? Conclusion::kEquivalent : Conclusion::kInconclusive;
}

// "the data cannot exclude |d'| up to 1.20" (or "d' down to -1.30" when only the low end
// reaches past the margin; "any d' above -0.27" when the interval is open above).
std::string cannot_exclude(double low, double high, double margin) {
  if (std::isinf(high) && high > 0) return "any d' above " + dprime_text(low);
  if (std::isinf(low) && low < 0) return "any d' below " + dprime_text(high);
  if (high >= margin || !(low <= -margin)) return "|d'| up to " + dprime_text(high);
  return "d' down to " + dprime_text(low);
}

}  // namespace

IdentifyReal identify_verdict(IdentifyReal result, double confidence) {
  const Forced2Result& panel = result.panel;
  const std::string level = confidence_text(confidence);
  const std::string margin = dprime_text(result.margin);
  const std::string numbers = dprime_with_interval(panel.dprime, panel.ci_low, panel.ci_high) +
                              ", " + std::to_string(panel.correct) + " of " +
                              std::to_string(panel.n) + " correct";
  const std::string equivalence_p = "equivalence " + p_value_text(panel.p_equivalence);
  result.conclusion = conclude(panel.p, panel.ci_low, panel.ci_high, result.margin, confidence);
  switch (result.conclusion) {
    case Conclusion::kEquivalent:
      result.verdict = "indistinguishable: |d'| below " + margin + " with " + level +
                       " confidence: " + numbers + " (" + equivalence_p + ", two one-sided tests)";
      break;
    case Conclusion::kDifferentWithinMargin:
      result.verdict =
          "a difference smaller than the margin: the panel told the doors apart "
          "above chance (" +
          p_value_text(panel.p) + "), but |d'| is below " + margin + " with " + level +
          " confidence: " + numbers;
      break;
    case Conclusion::kDifferent:
      result.verdict =
          std::string(panel.pc > 0.5 ? "the panel could tell the virtual door from the real one: "
                                     : "the panel took the virtual door for the real one more "
                                       "often than chance: ") +
          numbers + " (" + p_value_text(panel.p) + ")";
      break;
    case Conclusion::kInconclusive:
      result.verdict = "no evidence of a difference, but the data cannot exclude " +
                       cannot_exclude(panel.ci_low, panel.ci_high, result.margin) + ": " + numbers +
                       " (" + p_value_text(panel.p) + "; equivalence margin " + margin + ")";
      break;
  }
  return result;
}

std::optional<IdentifyReal> identify_real(const TrialsTable& table, const std::string& real_variant,
                                          double confidence, double margin) {
  std::vector<std::string> order;
  std::map<std::string, std::pair<int, int>> counts;  // participant -> (correct, n)
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    if (!is_question(table.value(r, "question"), QuestionKind::kIdentifyReal)) continue;
    const std::string& answer = table.value(r, "answer");
    if (answer != "1" && answer != "2")
      throw TrialsTableError(
          table.source, table.line_numbers[r],
          "answer '" + answer + "' to an identify-real question (expected 1 or 2)");
    const std::string& first = table.value(r, "first");
    const std::string& second = table.value(r, "second");
    if ((first == real_variant) == (second == real_variant))
      throw TrialsTableError(table.source, table.line_numbers[r],
                             "an identify-real trial must present the real door ('" + real_variant +
                                 "') once; it presents '" + first + "' and '" + second + "'");
    const std::string& participant = table.value(r, "participant");
    if (counts.count(participant) == 0) order.push_back(participant);
    auto& [correct, n] = counts[participant];
    correct += (answer == "1") == (first == real_variant) ? 1 : 0;
    ++n;
  }
  if (order.empty()) return std::nullopt;
  IdentifyReal result;
  int correct = 0, n = 0;
  for (const std::string& participant : order) {
    const auto [c, m] = counts[participant];
    Forced2Result one = forced_choice_2afc(c, m, confidence, margin);
    one.participant = participant;
    result.participants.push_back(one);
    correct += c;
    n += m;
  }
  result.panel = forced_choice_2afc(correct, n, confidence, margin);
  result.margin = margin;
  return identify_verdict(std::move(result), confidence);
}

namespace {

// The likelihood's maximum, or its supremum when d' is infinite: then τ follows d' so that
// the answers nobody gave get probability 0 and the others their shares.
double two_ac_top(const TwoAcResult& r) {
  const double n1 = r.prefer_first, n2 = r.no_preference, n3 = r.prefer_second;
  if (std::isfinite(r.dprime)) return two_ac_log_likelihood(r.tau, r.dprime, n1, n2, n3);
  double top = 0;
  for (const double count : {n1, n2, n3})
    if (count > 0) top += count * std::log(count / (n1 + n2 + n3));
  return top;
}

// The profile-likelihood interval of d' (open on the side of an infinite estimate), the
// likelihood-root test of d' = 0 and the two one-sided tests against ±margin.
void two_ac_profile(TwoAcResult& r, double confidence) {
  const double n1 = r.prefer_first, n2 = r.no_preference, n3 = r.prefer_second;
  const double top = two_ac_top(r);
  const auto root = [&](double d) {
    const double drop = std::max(0.0, top - profile_log_likelihood(d, n1, n2, n3));
    return (r.dprime >= d ? 1.0 : -1.0) * std::sqrt(2 * drop);
  };
  const double z = z_for(confidence);
  const double step = std::isfinite(r.se_dprime) && r.se_dprime > 0 ? r.se_dprime : 0.5;
  // sign −1: the lower limit (root = z); +1: the upper (root = −z). "Inside" the interval,
  // sign · f > 0.
  auto solve = [&](double sign) {
    if (std::isinf(r.dprime) && (r.dprime > 0) == (sign > 0)) return r.dprime;
    const auto f = [&](double d) { return root(d) + sign * z; };
    double inner = r.dprime;
    if (!std::isfinite(inner)) {  // from 0 towards the infinite estimate until inside
      inner = 0;
      for (int k = 0; k < 60 && !(sign * f(inner) > 0); ++k)
        inner -= sign * std::max(1.0, std::abs(inner));
    }
    double outer = inner + sign * step;
    for (int k = 0; k < 60 && sign * f(outer) > 0; ++k) inner = outer, outer += sign * step;
    std::uintmax_t iterations = 200;
    const auto bracket = boost::math::tools::toms748_solve(
        f, std::min(inner, outer), std::max(inner, outer),
        boost::math::tools::eps_tolerance<double>(48), iterations);
    return (bracket.first + bracket.second) / 2;
  };
  r.ci_low = solve(-1);
  r.ci_high = solve(+1);
  r.p = 2 * phi_upper(std::abs(root(0)));
  // H0 d' ≥ margin is rejected by a root far below 0 at the margin; H0 d' ≤ −margin by one
  // far above 0 at −margin.
  r.p_equivalence = std::max(phi_lower(root(r.margin)), phi_upper(root(-r.margin)));
}

// The pair's verdict in words, naming the variants.
void two_ac_verdict(TwoAcResult& r, double confidence) {
  const std::string numbers = dprime_with_interval(r.dprime, r.ci_low, r.ci_high) + ", " +
                              std::to_string(r.prefer_first) + " prefer " + r.first + ", " +
                              std::to_string(r.no_preference) + " same, " +
                              std::to_string(r.prefer_second) + " prefer " + r.second;
  const std::string level = confidence_text(confidence), margin = dprime_text(r.margin);
  const std::string preferred =
      r.dprime > 0 ? r.second + " preferred to " + r.first : r.first + " preferred to " + r.second;
  r.conclusion = conclude(r.p, r.ci_low, r.ci_high, r.margin, confidence);
  switch (r.conclusion) {
    case Conclusion::kEquivalent:
      r.verdict = "indistinguishable: |d'| below " + margin + " with " + level +
                  " confidence: " + numbers + " (equivalence " + p_value_text(r.p_equivalence) +
                  ", two one-sided tests)";
      break;
    case Conclusion::kDifferentWithinMargin:
      r.verdict = "a preference smaller than the margin: " + preferred + " above chance (" +
                  p_value_text(r.p) + "), but |d'| is below " + margin + " with " + level +
                  " confidence: " + numbers;
      break;
    case Conclusion::kDifferent:
      r.verdict = preferred + ": " + numbers + " (" + p_value_text(r.p) + ")";
      break;
    case Conclusion::kInconclusive:
      r.verdict = "no evidence of a preference, but the data cannot exclude " +
                  cannot_exclude(r.ci_low, r.ci_high, r.margin) + ": " + numbers + " (" +
                  p_value_text(r.p) + "; equivalence margin " + margin + ")";
      break;
  }
}

}  // namespace

TwoAcResult two_ac(int prefer_first, int no_preference, int prefer_second, double confidence,
                   double margin, const std::string& first, const std::string& second) {
  if (prefer_first < 0 || no_preference < 0 || prefer_second < 0 ||
      prefer_first + no_preference + prefer_second == 0)
    throw std::invalid_argument("2-AC: need non-negative counts, not all zero");
  if (!(margin > 0) || !std::isfinite(margin))
    throw std::invalid_argument("2-AC: the equivalence margin must be a positive d'");
  TwoAcResult r;
  r.first = first;
  r.second = second;
  r.margin = margin;
  r.prefer_first = prefer_first;
  r.no_preference = no_preference;
  r.prefer_second = prefer_second;
  if (prefer_first == 0 && prefer_second == 0) {
    r.tau = r.dprime = r.se_tau = r.se_dprime = r.ci_low = r.ci_high = r.p = kNaN;
    r.p_equivalence = kNaN;
    r.note = "no interval: every answer was 'same', which the model cannot turn into a d'";
    r.verdict = "no d': every answer was 'same' (" + std::to_string(no_preference) + " answers)";
    return r;
  }
  const double n = prefer_first + no_preference + prefer_second;
  const double gamma1 = prefer_first / n, gamma2 = (prefer_first + no_preference) / n;
  if (prefer_first == 0 || prefer_second == 0) {
    r.dprime = prefer_first == 0 ? kInf : -kInf;
    r.tau = r.se_tau = r.se_dprime = kNaN;
    r.note = "nobody preferred " + (prefer_first == 0 ? first : second) + ": d' is infinite and " +
             "its interval open " + (prefer_first == 0 ? "above" : "below");
  } else {
    const double q1 = normal_quantile(gamma1), q2 = normal_quantile(gamma2);
    const double z1 = kSqrt2 * q1, z2 = kSqrt2 * q2;
    r.tau = (z2 - z1) / 2;
    r.dprime = -(z1 + z2) / 2;
    // Delta method on the multinomial proportions (the model is saturated, so this is the
    // inverse of the observed information at the estimate).
    const double a1 = kSqrt2 / boost::math::pdf(boost::math::normal(), q1);
    const double a2 = kSqrt2 / boost::math::pdf(boost::math::normal(), q2);
    const double v11 = gamma1 * (1 - gamma1) / n, v22 = gamma2 * (1 - gamma2) / n,
                 v12 = gamma1 * (1 - gamma2) / n;
    const double var_tau = (a1 * a1 * v11 - 2 * a1 * a2 * v12 + a2 * a2 * v22) / 4;
    const double var_d = (a1 * a1 * v11 + 2 * a1 * a2 * v12 + a2 * a2 * v22) / 4;
    r.se_tau = std::sqrt(var_tau);
    r.se_dprime = std::sqrt(var_d);
    if (no_preference == 0) r.note = "nobody answered 'same': tau at its bound 0";
  }
  two_ac_profile(r, confidence);
  two_ac_verdict(r, confidence);
  return r;
}

std::vector<TwoAcResult> two_ac_pairs(const TrialsTable& table, double confidence, double margin) {
  struct Counts {
    std::string a, b;
    int n[3] = {0, 0, 0};  // prefer a, none, prefer b
  };
  std::vector<Counts> pairs;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    if (!is_question(table.value(r, "question"), QuestionKind::kPreference2ac)) continue;
    const std::string& first = table.value(r, "first");
    const std::string& second = table.value(r, "second");
    const std::string& answer = table.value(r, "answer");
    if (answer != "1" && answer != "2" && answer != "same")
      throw TrialsTableError(
          table.source, table.line_numbers[r],
          "answer '" + answer + "' to a preference-2ac question (expected 1, 2 or same)");
    auto at = std::find_if(pairs.begin(), pairs.end(), [&](const Counts& c) {
      return (c.a == first && c.b == second) || (c.a == second && c.b == first);
    });
    if (at == pairs.end()) at = pairs.insert(pairs.end(), Counts{first, second, {0, 0, 0}});
    if (answer == "same") {
      ++at->n[1];
    } else {
      const std::string& preferred = answer == "1" ? first : second;
      ++at->n[preferred == at->a ? 0 : 2];
    }
  }
  std::vector<TwoAcResult> results;
  for (const Counts& c : pairs) {
    results.push_back(two_ac(c.n[0], c.n[1], c.n[2], confidence, margin, c.a, c.b));
  }
  return results;
}

nlohmann::json identify_real_json(const IdentifyReal& result) {
  auto one = [](const Forced2Result& r) {
    nlohmann::json j = {{"n", r.n},
                        {"correct", r.correct},
                        {"pc", r.pc},
                        {"pc_low", r.pc_low},
                        {"pc_high", r.pc_high},
                        {"dprime", json_number(r.dprime)},
                        {"ci_low", json_number(r.ci_low)},
                        {"ci_high", json_number(r.ci_high)},
                        {"p", r.p},
                        {"p_equivalence", r.p_equivalence}};
    if (!r.participant.empty()) j["participant"] = r.participant;
    return j;
  };
  nlohmann::json participants = nlohmann::json::array();
  for (const Forced2Result& r : result.participants) participants.push_back(one(r));
  return {{"panel", one(result.panel)},
          {"participants", participants},
          {"equivalence_margin", result.margin},
          {"conclusion", conclusion_name(result.conclusion)},
          {"verdict", result.verdict}};
}

nlohmann::json two_ac_json(const std::vector<TwoAcResult>& results) {
  nlohmann::json out = nlohmann::json::array();
  for (const TwoAcResult& r : results) {
    out.push_back({{"first", r.first},
                   {"second", r.second},
                   {"prefer_first", r.prefer_first},
                   {"no_preference", r.no_preference},
                   {"prefer_second", r.prefer_second},
                   {"tau", json_number(r.tau)},
                   {"se_tau", json_number(r.se_tau)},
                   {"dprime", json_number(r.dprime)},
                   {"se_dprime", json_number(r.se_dprime)},
                   {"ci_low", json_number(r.ci_low)},
                   {"ci_high", json_number(r.ci_high)},
                   {"p", json_number(r.p)},
                   {"p_equivalence", json_number(r.p_equivalence)},
                   {"equivalence_margin", r.margin},
                   {"conclusion", conclusion_name(r.conclusion)},
                   {"verdict", r.verdict},
                   {"note", r.note}});
  }
  return out;
}

}  // namespace doorbench::study
