#include "study/statistics/ratings.h"

#include <algorithm>
#include <boost/math/distributions/normal.hpp>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "study/question.h"
#include "study/statistics/gauss_hermite.h"
#include "study/statistics/logistic.h"
#include "study/statistics/numeric_minimize.h"

namespace doorbench::study {
namespace {

using statistics::minimize;
using statistics::numeric_hessian;

// log P(Y = y | eta) and its first two derivatives in eta, for thresholds `theta`
// (C - 1 of them for C categories; y in 0..C-1).
struct LogProb {
  double value, d1, d2;
};

LogProb log_prob(int y, double eta, const std::vector<double>& theta) {
  const int cuts = static_cast<int>(theta.size());
  // Upper cut a = theta_y - eta (absent for the top category), lower b = theta_{y-1} - eta.
  const bool has_upper = y < cuts;
  const bool has_lower = y > 0;
  const double a = has_upper ? theta[y] - eta : 0.0;
  const double b = has_lower ? theta[y - 1] - eta : 0.0;
  const double fa_cdf = has_upper ? logistic(a) : 1.0;
  const double fb_cdf = has_lower ? logistic(b) : 0.0;
  double p;
  if (!has_lower) {
    p = fa_cdf;
  } else if (!has_upper) {
    p = logistic(-b);
  } else if (a + b > 0.0) {
    p = logistic(-b) - logistic(-a);  // both in the upper tail: subtract the small complements
  } else {
    p = fa_cdf - fb_cdf;
  }
  const double fa = has_upper ? fa_cdf * (1.0 - fa_cdf) : 0.0;
  const double fb = has_lower ? fb_cdf * (1.0 - fb_cdf) : 0.0;
  const double dfa = has_upper ? fa * (1.0 - 2.0 * fa_cdf) : 0.0;
  const double dfb = has_lower ? fb * (1.0 - 2.0 * fb_cdf) : 0.0;
  if (!(p > 0.0)) return {-std::numeric_limits<double>::infinity(), 0.0, 0.0};
  const double d1 = -(fa - fb) / p;
  const double d2 = (dfa - dfb) / p - d1 * d1;
  return {std::log(p), d1, d2};
}

struct Observation {
  int variant;
  int category;  // 0-based index among the used categories
};

struct Data {
  std::vector<std::vector<Observation>> by_participant;
  int categories = 0;  // used
  int variants = 0;
};

struct Parameters {
  std::vector<double> theta;
  std::vector<double> beta;  // beta[0] = 0
  double sigma = 0.0;
};

Parameters unpack(const Eigen::VectorXd& x, const Data& data, bool random_effect) {
  Parameters p;
  const int cuts = data.categories - 1;
  p.theta.resize(cuts);
  for (int k = 0; k < cuts; ++k) p.theta[k] = k == 0 ? x[0] : p.theta[k - 1] + std::exp(x[k]);
  p.beta.assign(data.variants, 0.0);
  for (int v = 1; v < data.variants; ++v) p.beta[v] = x[cuts + v - 1];
  if (random_effect) p.sigma = std::exp(x[cuts + data.variants - 1]);
  return p;
}

// log of participant i's marginal likelihood by adaptive Gauss–Hermite quadrature.
double participant_log_likelihood(const std::vector<Observation>& rows, const Parameters& p,
                                  const statistics::GaussHermite& rule) {
  auto conditional = [&](double u, double* d1, double* d2) {
    double value = -0.5 * u * u - 0.5 * std::log(2.0 * std::numbers::pi);
    double g1 = -u, g2 = -1.0;
    for (const Observation& o : rows) {
      const LogProb lp = log_prob(o.category, p.beta[o.variant] + p.sigma * u, p.theta);
      value += lp.value;
      g1 += p.sigma * lp.d1;
      g2 += p.sigma * p.sigma * lp.d2;
    }
    if (d1) *d1 = g1;
    if (d2) *d2 = g2;
    return value;
  };
  // The conditional mode: g is concave (log-concave logistic model), Newton with halving.
  double u = 0.0, g1 = 0.0, g2 = -1.0;
  double value = conditional(u, &g1, &g2);
  for (int iteration = 0; iteration < 100 && std::abs(g1) > 1e-12; ++iteration) {
    double step = -g1 / g2;
    for (int halving = 0; halving < 50; ++halving) {
      double n1, n2;
      const double next = conditional(u + step, &n1, &n2);
      if (std::isfinite(next) && next >= value - 1e-14) {
        u += step;
        value = next;
        g1 = n1;
        g2 = n2;
        break;
      }
      step /= 2.0;
    }
  }
  if (!std::isfinite(value)) return value;
  const double scale = std::sqrt(-1.0 / g2);
  // ∫ e^{g(u)} du = √2 s Σ w_k e^{x_k²} e^{g(û + √2 s x_k)}, summed relative to e^{g(û)}.
  double sum = 0.0;
  for (std::size_t k = 0; k < rule.nodes.size(); ++k) {
    const double x = rule.nodes[k];
    sum += rule.weights[k] *
           std::exp(x * x + conditional(u + std::numbers::sqrt2 * scale * x, nullptr, nullptr) -
                    value);
  }
  return value + std::log(std::numbers::sqrt2 * scale * sum);
}

double negative_log_likelihood(const Eigen::VectorXd& x, const Data& data, bool random_effect,
                               const statistics::GaussHermite& rule) {
  const Parameters p = unpack(x, data, random_effect);
  double total = 0.0;
  for (const auto& rows : data.by_participant) {
    if (random_effect) {
      total += participant_log_likelihood(rows, p, rule);
    } else {
      for (const Observation& o : rows)
        total += log_prob(o.category, p.beta[o.variant], p.theta).value;
    }
  }
  return std::isfinite(total) ? -total : std::numeric_limits<double>::infinity();
}

Eigen::VectorXd start_values(const Data& data) {
  const int cuts = data.categories - 1;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(cuts + data.variants - 1);
  std::vector<double> counts(data.categories, 0.0);
  double total = 0.0;
  for (const auto& rows : data.by_participant) {
    for (const Observation& o : rows) counts[o.category] += 1.0, total += 1.0;
  }
  double cumulative = 0.0, previous = 0.0;
  for (int k = 0; k < cuts; ++k) {
    cumulative += counts[k];
    const double share = cumulative / total;
    const double theta = std::log(share / (1.0 - share));
    x[k] = k == 0 ? theta : std::log(std::max(theta - previous, 1e-3));
    previous = theta;
  }
  return x;
}

struct Fit {
  Eigen::VectorXd x;
  double log_likelihood = 0.0;
  bool converged = false;
};

Fit fit_model(const Data& data, bool random_effect, const statistics::GaussHermite& rule,
              const Eigen::VectorXd& start) {
  const statistics::Objective f = [&](const Eigen::VectorXd& x) {
    return negative_log_likelihood(x, data, random_effect, rule);
  };
  const auto result = minimize(f, start);
  return {result.x, -result.value, result.converged};
}

}  // namespace

std::string RatingsOptions::validate() const {
  if (quadrature_nodes < 1 || quadrature_nodes > 50) {
    return "quadrature_nodes must be 1..50 (1: Laplace), not " + std::to_string(quadrature_nodes);
  }
  if (!(confidence > 0.0 && confidence < 1.0)) {
    return "confidence must be in (0, 1), not " + std::to_string(confidence);
  }
  std::set<std::string> seen;
  for (const std::string& v : variant_order) {
    if (!seen.insert(v).second) return "variant_order names '" + v + "' twice";
  }
  return "";
}

AttributeRatings fit_attribute_ratings(std::span<const RatingObservation> observations,
                                       const RatingsOptions& options) {
  if (const std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument("ratings: " + problem);
  }
  if (observations.empty()) throw std::invalid_argument("ratings: no observations");
  AttributeRatings out;
  out.attribute = observations.front().attribute;
  out.categories = observations.front().categories;
  const std::string where = "ratings of '" + out.attribute + "': ";
  std::vector<std::string> variants = options.variant_order;
  std::vector<std::string> participants;
  std::set<int> used;
  for (const RatingObservation& o : observations) {
    if (o.attribute != out.attribute || o.categories != out.categories) {
      throw std::invalid_argument(where + "observations of '" + o.attribute + "' (" +
                                  std::to_string(o.categories) + " categories) mixed in");
    }
    if (o.rating < 1 || o.rating > o.categories) {
      throw std::invalid_argument(where + "rating " + std::to_string(o.rating) + " outside 1.." +
                                  std::to_string(o.categories));
    }
    if (std::find(variants.begin(), variants.end(), o.variant) == variants.end()) {
      if (!options.variant_order.empty()) {
        throw std::invalid_argument(where + "variant '" + o.variant + "' is not in variant_order");
      }
      variants.push_back(o.variant);
    }
    if (std::find(participants.begin(), participants.end(), o.participant) == participants.end()) {
      participants.push_back(o.participant);
    }
    used.insert(o.rating);
  }
  if (used.size() < 2) throw std::invalid_argument(where + "every rating is the same");
  if (variants.size() < 2) throw std::invalid_argument(where + "one variant only");
  out.used_categories.assign(used.begin(), used.end());

  Data data;
  data.categories = static_cast<int>(used.size());
  data.variants = static_cast<int>(variants.size());
  data.by_participant.resize(participants.size());
  for (const RatingObservation& o : observations) {
    const auto index = [](const auto& list, const auto& value) {
      return static_cast<int>(std::find(list.begin(), list.end(), value) - list.begin());
    };
    data.by_participant[index(participants, o.participant)].push_back(
        {index(variants, o.variant), index(out.used_categories, o.rating)});
  }
  out.observations = static_cast<int>(observations.size());
  out.participants = static_cast<int>(participants.size());

  const statistics::GaussHermite rule = statistics::gauss_hermite(options.quadrature_nodes);
  Fit fixed = fit_model(data, false, rule, start_values(data));
  Fit chosen = fixed;
  bool random_effect = false;
  if (options.random_effect && participants.size() > 1) {
    Eigen::VectorXd start(fixed.x.size() + 1);
    start << fixed.x, std::log(0.5);
    Fit mixed = fit_model(data, true, rule, start);
    // sigma at its boundary 0: the mixed model gains nothing, keep the fixed-effect one.
    if (mixed.log_likelihood > fixed.log_likelihood + 1e-6 &&
        std::exp(mixed.x[mixed.x.size() - 1]) > 1e-3) {
      chosen = mixed;
      random_effect = true;
    }
  }
  out.random_effect = random_effect;
  out.quadrature_nodes = random_effect ? options.quadrature_nodes : 0;
  out.log_likelihood = chosen.log_likelihood;
  out.converged = chosen.converged;
  const Parameters p = unpack(chosen.x, data, random_effect);
  out.thresholds = p.theta;
  out.participant_sd = p.sigma;

  const statistics::Objective f = [&](const Eigen::VectorXd& x) {
    return negative_log_likelihood(x, data, random_effect, rule);
  };
  const Eigen::MatrixXd covariance = numeric_hessian(f, chosen.x).inverse();
  const double z = boost::math::quantile(boost::math::normal(), 0.5 + options.confidence / 2.0);
  const int cuts = data.categories - 1;
  for (int v = 0; v < data.variants; ++v) {
    VariantEffect effect;
    effect.variant = variants[v];
    if (v > 0) {
      effect.estimate = p.beta[v];
      const double variance = covariance(cuts + v - 1, cuts + v - 1);
      effect.std_error =
          variance > 0.0 ? std::sqrt(variance) : std::numeric_limits<double>::quiet_NaN();
      effect.ci_low = effect.estimate - z * effect.std_error;
      effect.ci_high = effect.estimate + z * effect.std_error;
    }
    out.effects.push_back(effect);
  }
  if (random_effect) {
    const Eigen::Index last = chosen.x.size() - 1;
    out.participant_sd_std_error = p.sigma * std::sqrt(std::max(0.0, covariance(last, last)));
  }
  return out;
}

RatingsResult fit_ratings(std::span<const RatingObservation> observations,
                          const RatingsOptions& options) {
  std::vector<std::string> attributes;
  std::map<std::string, std::vector<RatingObservation>> by_attribute;
  for (const RatingObservation& o : observations) {
    if (!by_attribute.contains(o.attribute)) attributes.push_back(o.attribute);
    by_attribute[o.attribute].push_back(o);
  }
  RatingsResult result;
  for (const std::string& attribute : attributes) {
    result.attributes.push_back(fit_attribute_ratings(by_attribute[attribute], options));
  }
  return result;
}

nlohmann::json RatingsResult::to_json() const {
  nlohmann::json rows = nlohmann::json::array();
  for (const AttributeRatings& a : attributes) {
    for (std::size_t v = 0; v < a.effects.size(); ++v) {
      const VariantEffect& e = a.effects[v];
      rows.push_back({{"attribute", a.attribute},
                      {"variant", e.variant},
                      {"estimate", e.estimate},
                      {"ci_low", e.ci_low},
                      {"ci_high", e.ci_high},
                      {"std_error", e.std_error},
                      {"reference", v == 0}});
    }
  }
  return rows;
}

nlohmann::json RatingsResult::models_json() const {
  nlohmann::json rows = nlohmann::json::array();
  for (const AttributeRatings& a : attributes) {
    rows.push_back({{"attribute", a.attribute},
                    {"categories", a.categories},
                    {"used_categories", a.used_categories},
                    {"thresholds", a.thresholds},
                    {"model", a.random_effect ? "clmm" : "clm"},
                    {"participant_sd", a.participant_sd},
                    {"participant_sd_std_error", a.participant_sd_std_error},
                    {"quadrature_nodes", a.quadrature_nodes},
                    {"log_likelihood", a.log_likelihood},
                    {"observations", a.observations},
                    {"participants", a.participants},
                    {"converged", a.converged}});
  }
  return rows;
}

namespace {

std::optional<int> parse_int(std::string_view text) {
  int value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || text.empty()) return std::nullopt;
  return value;
}

}  // namespace

std::vector<RatingObservation> rating_observations(const TrialsTable& table) {
  std::vector<RatingObservation> out;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    const std::string& question = table.value(r, "question");
    if (spelled_kind(question) != QuestionKind::kRating) continue;
    const int line = table.line_numbers[r];
    const std::optional<Question> asked = Question::parse(question);
    if (!asked || asked->subject.empty()) {
      throw TrialsTableError(table.source, line,
                             "question '" + question + "' is not rating:ATTRIBUTE:K with K in 2.." +
                                 std::to_string(Question::kMaxRatingScale));
    }
    const std::string& attribute = asked->subject;
    const int k = asked->scale;
    const std::string& answer = table.value(r, "answer");
    std::istringstream words(answer);
    std::string w1, w2, extra;
    words >> w1 >> w2 >> extra;
    const auto r1 = parse_int(w1), r2 = parse_int(w2);
    if (!r1 || !r2 || !extra.empty() || *r1 < 1 || *r1 > k || *r2 < 1 || *r2 > k) {
      throw TrialsTableError(table.source, line,
                             "answer '" + answer + "' is not two ratings 1.." + std::to_string(k) +
                                 " (first variant's, second's)");
    }
    const std::string& participant = table.value(r, "participant");
    out.push_back({participant, attribute, k, table.value(r, "first"), *r1});
    out.push_back({participant, attribute, k, table.value(r, "second"), *r2});
  }
  return out;
}

}  // namespace doorbench::study
