#include "study/statistics/discrimination.h"

#include <algorithm>
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

#include "haptic/ab_trials.h"
#include "core/numbers.h"
#include "study/statistics/json_number.h"

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


std::string format_number(double value) {
  if (std::isnan(value)) return "n/a";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char text[32];
  std::snprintf(text, sizeof text, "%.2f", value);
  return text;
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

Forced2Result forced_choice_2afc(int correct, int n, double confidence) {
  if (n <= 0 || correct < 0 || correct > n)
    throw std::invalid_argument("2-AFC: need 0 <= correct <= n and n > 0");
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
  r.p = haptic::binomial_two_sided_p(correct, n);
  return r;
}

namespace {

std::string identify_verdict(const Forced2Result& panel, double confidence) {
  const std::string numbers =
      "d' " + format_number(panel.dprime) + " [" + format_number(panel.ci_low) + ", " +
      format_number(panel.ci_high) + "] (" + std::to_string(panel.correct) + " of " +
      std::to_string(panel.n) + " correct, p = " + format_number(panel.p) + ")";
  if (panel.p >= 1 - confidence)
    return "the panel could not tell the virtual door from the real one: " + numbers;
  if (panel.pc > 0.5) return "the panel could tell the virtual door from the real one: " + numbers;
  return "the panel took the virtual door for the real one more often than chance: " + numbers;
}

}  // namespace

std::optional<IdentifyReal> identify_real(const TrialsTable& table, const std::string& real_variant,
                                          double confidence) {
  std::vector<std::string> order;
  std::map<std::string, std::pair<int, int>> counts;  // participant -> (correct, n)
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    if (table.value(r, "question") != "identify-real") continue;
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
    Forced2Result one = forced_choice_2afc(c, m, confidence);
    one.participant = participant;
    result.participants.push_back(one);
    correct += c;
    n += m;
  }
  result.panel = forced_choice_2afc(correct, n, confidence);
  result.verdict = identify_verdict(result.panel, confidence);
  return result;
}

namespace {

// The profile-likelihood interval of d' and the likelihood-root test of d' = 0.
void two_ac_profile(TwoAcResult& r, double confidence) {
  const double n1 = r.prefer_first, n2 = r.no_preference, n3 = r.prefer_second;
  const double top = two_ac_log_likelihood(r.tau, r.dprime, n1, n2, n3);
  const auto root = [&](double d) {
    const double drop = std::max(0.0, top - profile_log_likelihood(d, n1, n2, n3));
    return (r.dprime >= d ? 1.0 : -1.0) * std::sqrt(2 * drop);
  };
  const double z = z_for(confidence);
  const double step = std::isfinite(r.se_dprime) && r.se_dprime > 0 ? r.se_dprime : 0.5;
  auto solve = [&](double sign) {  // sign −1: lower limit (root = z); +1: upper (root = −z)
    double inner = r.dprime, outer = r.dprime + sign * step;
    for (int k = 0; k < 60 && sign * root(outer) > -z; ++k) inner = outer, outer += sign * step;
    const auto f = [&](double d) { return root(d) + sign * z; };
    std::uintmax_t iterations = 200;
    const auto bracket = boost::math::tools::toms748_solve(
        f, std::min(inner, outer), std::max(inner, outer),
        boost::math::tools::eps_tolerance<double>(48), iterations);
    return (bracket.first + bracket.second) / 2;
  };
  r.ci_low = solve(-1);
  r.ci_high = solve(+1);
  r.p = 2 * phi_upper(std::abs(root(0)));
}

}  // namespace

TwoAcResult two_ac(int prefer_first, int no_preference, int prefer_second, double confidence) {
  if (prefer_first < 0 || no_preference < 0 || prefer_second < 0 ||
      prefer_first + no_preference + prefer_second == 0)
    throw std::invalid_argument("2-AC: need non-negative counts, not all zero");
  TwoAcResult r;
  r.prefer_first = prefer_first;
  r.no_preference = no_preference;
  r.prefer_second = prefer_second;
  const double n = prefer_first + no_preference + prefer_second;
  const double gamma1 = prefer_first / n, gamma2 = (prefer_first + no_preference) / n;
  if (prefer_first == 0 || prefer_second == 0) {
    r.dprime = prefer_first == 0 ? kInf : -kInf;
    r.tau = r.se_tau = r.se_dprime = r.ci_low = r.ci_high = kNaN;
    r.p = kNaN;
    r.note = "not estimable: nobody preferred " +
             std::string(prefer_first == 0 ? "the first" : "the second") + " variant";
    return r;
  }
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
  two_ac_profile(r, confidence);
  return r;
}

std::vector<TwoAcResult> two_ac_pairs(const TrialsTable& table, double confidence) {
  struct Counts {
    std::string a, b;
    int n[3] = {0, 0, 0};  // prefer a, none, prefer b
  };
  std::vector<Counts> pairs;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    if (table.value(r, "question") != "preference-2ac") continue;
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
    TwoAcResult r = two_ac(c.n[0], c.n[1], c.n[2], confidence);
    r.first = c.a;
    r.second = c.b;
    results.push_back(r);
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
                        {"p", r.p}};
    if (!r.participant.empty()) j["participant"] = r.participant;
    return j;
  };
  nlohmann::json participants = nlohmann::json::array();
  for (const Forced2Result& r : result.participants) participants.push_back(one(r));
  return {
      {"panel", one(result.panel)}, {"participants", participants}, {"verdict", result.verdict}};
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
                   {"note", r.note}});
  }
  return out;
}

}  // namespace doorbench::study
