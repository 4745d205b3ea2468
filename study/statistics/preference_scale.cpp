#include "study/statistics/preference_scale.h"

#include <Eigen/Dense>
#include <algorithm>
#include <boost/math/distributions/normal.hpp>
#include <cmath>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <tuple>

#include "core/json_number.h"
#include "core/numbers.h"
#include "core/percentile.h"
#include "core/seeded_random.h"
#include "study/question.h"
#include "study/statistics/quasi_variance.h"

namespace doorbench::study {
namespace {

// Answers of one ordered pair (first, second), summed over trials.
struct Cell {
  int first = 0, second = 0;
  double n_first = 0, n_second = 0, n_same = 0;
};

// Cells of the trials of the given participants (each participant as often as listed).
std::vector<Cell> cells_of(const PairData& data, const std::vector<int>& participant_weights) {
  std::map<std::pair<int, int>, Cell> cells;
  for (const PairTrial& trial : data.trials) {
    const double weight = participant_weights[std::size_t(trial.participant)];
    if (weight == 0) continue;
    Cell& cell = cells[{trial.first, trial.second}];
    cell.first = trial.first;
    cell.second = trial.second;
    (trial.answer == 1 ? cell.n_first : trial.answer == 2 ? cell.n_second : cell.n_same) += weight;
  }
  std::vector<Cell> out;
  for (const auto& [key, cell] : cells) out.push_back(cell);
  return out;
}

// The free parameters: worths of the variants other than the reference, then δ, then log ν.
struct Layout {
  int variants = 0, reference = 0;
  bool order = false, ties = false;
  int worth_index(int variant) const {  // -1 for the reference
    if (variant == reference) return -1;
    return variant < reference ? variant : variant - 1;
  }
  int order_index() const { return variants - 1; }
  int nu_index() const { return variants - 1 + (order ? 1 : 0); }
  int size() const { return variants - 1 + (order ? 1 : 0) + (ties ? 1 : 0); }
};

// The rows of the multinomial logit's design for one cell: η = X θ for the outcomes first,
// second, same (the last only with ties).
Eigen::MatrixXd cell_design(const Layout& layout, const Cell& cell) {
  const int outcomes = layout.ties ? 3 : 2;
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(outcomes, layout.size());
  const int i = layout.worth_index(cell.first), j = layout.worth_index(cell.second);
  if (i >= 0) x(0, i) += 1;
  if (layout.order) x(0, layout.order_index()) += 1;
  if (j >= 0) x(1, j) += 1;
  if (layout.ties) {
    x.row(2) = 0.5 * (x.row(0) + x.row(1));
    x(2, layout.nu_index()) += 1;
  }
  return x;
}

struct Evaluation {
  double log_likelihood = 0;
  Eigen::VectorXd gradient;
  Eigen::MatrixXd information;  // minus the Hessian
};

Evaluation evaluate(const Layout& layout, const std::vector<Cell>& cells,
                    const Eigen::VectorXd& theta) {
  Evaluation e;
  e.gradient = Eigen::VectorXd::Zero(layout.size());
  e.information = Eigen::MatrixXd::Zero(layout.size(), layout.size());
  for (const Cell& cell : cells) {
    const Eigen::MatrixXd x = cell_design(layout, cell);
    Eigen::VectorXd counts(x.rows());
    counts(0) = cell.n_first;
    counts(1) = cell.n_second;
    if (layout.ties) counts(2) = cell.n_same;
    const double n = counts.sum();
    const Eigen::VectorXd eta = x * theta;
    const double top = eta.maxCoeff();
    const Eigen::VectorXd expd = (eta.array() - top).exp().matrix();
    const double log_sum = top + std::log(expd.sum());
    const Eigen::VectorXd p = expd / expd.sum();
    e.log_likelihood += counts.dot(eta) - n * log_sum;
    e.gradient += x.transpose() * (counts - n * p);
    const Eigen::MatrixXd w = n * (Eigen::MatrixXd(p.asDiagonal()) - p * p.transpose());
    e.information += x.transpose() * w * x;
  }
  return e;
}

// Newton–Raphson with step halving; nullopt when it does not converge or runs off to
// infinity (a variant that never won or never lost).
std::optional<std::pair<Eigen::VectorXd, int>> newton(const Layout& layout,
                                                      const std::vector<Cell>& cells) {
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(layout.size());
  Evaluation e = evaluate(layout, cells, theta);
  for (int iteration = 1; iteration <= 200; ++iteration) {
    Eigen::LDLT<Eigen::MatrixXd> solver(e.information);
    if (solver.info() != Eigen::Success || !solver.isPositive()) return std::nullopt;
    Eigen::VectorXd step = solver.solve(e.gradient);
    if (!step.allFinite()) return std::nullopt;
    double scale = 1;
    Evaluation next = evaluate(layout, cells, theta + step);
    while (!(next.log_likelihood >= e.log_likelihood - 1e-12) && scale > 1e-10) {
      scale /= 2;
      next = evaluate(layout, cells, theta + scale * step);
    }
    theta += scale * step;
    e = next;
    if (theta.cwiseAbs().maxCoeff() > 40) return std::nullopt;
    if ((scale * step).cwiseAbs().maxCoeff() < 1e-11) return std::pair{theta, iteration};
  }
  return std::nullopt;
}

int reference_index(const PairData& data, const PreferenceOptions& options) {
  if (options.reference.empty()) return 0;
  for (std::size_t v = 0; v < data.variants.size(); ++v) {
    if (data.variants[v] == options.reference) return int(v);
  }
  throw PreferenceScaleError("reference variant '" + options.reference +
                             "' is not in any preference trial");
}

// The message for data whose likelihood has no finite maximum.
std::string separation_message(const PairData& data) {
  std::vector<int> wins(data.variants.size()), losses(data.variants.size());
  for (const PairTrial& t : data.trials) {
    if (t.answer == 1) ++wins[std::size_t(t.first)], ++losses[std::size_t(t.second)];
    if (t.answer == 2) ++wins[std::size_t(t.second)], ++losses[std::size_t(t.first)];
  }
  for (std::size_t v = 0; v < data.variants.size(); ++v) {
    if (wins[v] == 0)
      return "variant '" + data.variants[v] + "' was never preferred: its worth is -infinity";
    if (losses[v] == 0)
      return "variant '" + data.variants[v] + "' was always preferred: its worth is +infinity";
  }
  return "the answers do not determine a finite scale (each variant must be compared, "
         "directly or through others, with every other, and win and lose somewhere)";
}

}  // namespace

bool PairData::has_ties() const {
  return std::any_of(trials.begin(), trials.end(),
                     [](const PairTrial& t) { return t.answer == 0; });
}

bool PairData::has_both_orders() const {
  std::set<std::pair<int, int>> seen;
  for (const PairTrial& t : trials) seen.insert({t.first, t.second});
  return std::any_of(seen.begin(), seen.end(), [&](const auto& pair) {
    return seen.count({pair.second, pair.first}) > 0;
  });
}

PairData pair_data(const TrialsTable& table) {
  PairData data;
  auto index = [](std::vector<std::string>& names, const std::string& name) {
    const auto at = std::find(names.begin(), names.end(), name);
    if (at != names.end()) return int(at - names.begin());
    names.push_back(name);
    return int(names.size() - 1);
  };
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    const std::string& question = table.value(r, "question");
    const std::optional<Question> asked = Question::parse(question);
    if (!asked || !asked->is_preference()) continue;
    const bool two_ac = asked->kind == QuestionKind::kPreference2ac;
    const std::string& answer = table.value(r, "answer");
    PairTrial trial;
    if (answer == "1") {
      trial.answer = 1;
    } else if (answer == "2") {
      trial.answer = 2;
    } else if (answer == "same" && two_ac) {
      trial.answer = 0;
    } else {
      throw TrialsTableError(table.source, table.line_numbers[r],
                             "answer '" + answer + "' to a " + question + " question (expected " +
                                 (two_ac ? "1, 2 or same)" : "1 or 2)"));
    }
    const std::string& first = table.value(r, "first");
    const std::string& second = table.value(r, "second");
    if (first.empty() || second.empty())
      throw TrialsTableError(table.source, table.line_numbers[r],
                             "a " + question + " trial without a variant in '" +
                                 (first.empty() ? "first" : "second") + "'");
    if (first == second)
      throw TrialsTableError(table.source, table.line_numbers[r],
                             "a " + question + " trial compares '" + first + "' with itself");
    trial.first = index(data.variants, first);
    trial.second = index(data.variants, second);
    trial.participant = index(data.participants, table.value(r, "participant"));
    data.trials.push_back(trial);
  }
  return data;
}

std::string PreferenceOptions::validate() const {
  if (bootstrap_replicates < 0) return "bootstrap_replicates must be >= 0";
  if (bootstrap_replicates > 0 && bootstrap_replicates < 100)
    return "bootstrap_replicates must be 0 (none) or >= 100";
  if (min_bootstrap_participants < 2) return "min_bootstrap_participants must be >= 2";
  if (!(confidence > 0.5 && confidence < 1)) return "confidence must be in (0.5, 1)";
  return "";
}

std::optional<PointFit> fit_point(const PairData& data, int reference, bool order, bool ties) {
  Layout layout{int(data.variants.size()), reference, order, ties};
  if (layout.variants < 2) return std::nullopt;
  const std::vector<Cell> cells = cells_of(data, std::vector<int>(data.participants.size(), 1));
  const auto solved = newton(layout, cells);
  if (!solved) return std::nullopt;
  const auto& [theta, iterations] = *solved;
  const Evaluation e = evaluate(layout, cells, theta);
  PointFit fit;
  fit.free_parameters = layout.size();
  fit.worths.assign(std::size_t(layout.variants), 0.0);
  for (int v = 0; v < layout.variants; ++v) {
    const int k = layout.worth_index(v);
    if (k >= 0) fit.worths[std::size_t(v)] = theta(k);
  }
  if (order) fit.order = theta(layout.order_index());
  if (ties) fit.log_nu = theta(layout.nu_index());
  const Eigen::MatrixXd covariance = e.information.inverse();
  fit.covariance.assign(covariance.data(), covariance.data() + covariance.size());
  fit.log_likelihood = e.log_likelihood;
  fit.iterations = iterations;
  return fit;
}

namespace {

// The bootstrap replicates of the free parameters: participants drawn with replacement,
// the model refitted to each resample. Failed fits (separation) are counted, not kept.
struct Replicates {
  std::vector<Eigen::VectorXd> thetas;
  int failed = 0;
};

Replicates bootstrap(const PairData& data, const Layout& layout, const PreferenceOptions& options,
                     const std::function<void(int, int)>& progress) {
  Replicates out;
  std::mt19937_64 generator(options.seed);
  const int people = int(data.participants.size());
  if (progress) progress(0, options.bootstrap_replicates);
  for (int b = 0; b < options.bootstrap_replicates; ++b) {
    if (stop_requested(options.stop_requested)) {
      throw StopRequested("the preference scale's bootstrap");
    }
    std::vector<int> weights(std::size_t(people), 0);
    for (int k = 0; k < people; ++k)
      ++weights[std::size_t(uniform_below(generator, std::uint64_t(people)))];
    const auto solved = newton(layout, cells_of(data, weights));
    if (solved) {
      out.thetas.push_back(solved->first);
    } else {
      ++out.failed;
    }
    if (progress && ((b + 1) % 50 == 0 || b + 1 == options.bootstrap_replicates))
      progress(b + 1, options.bootstrap_replicates);
  }
  return out;
}

// Normal draws of the free parameters from the Wald sampling distribution.
std::vector<Eigen::VectorXd> normal_draws(const Eigen::VectorXd& theta,
                                          const Eigen::MatrixXd& covariance, std::uint64_t seed,
                                          int count) {
  std::mt19937_64 generator(seed);
  const Eigen::MatrixXd root = Eigen::LLT<Eigen::MatrixXd>(covariance).matrixL();
  std::vector<Eigen::VectorXd> draws;
  for (int d = 0; d < count; ++d) {
    Eigen::VectorXd z(theta.size());
    for (Eigen::Index k = 0; k < z.size(); ++k) z(k) = standard_normal(generator);
    draws.push_back(theta + root * z);
  }
  return draws;
}

Estimate estimate_of(double value, double se_wald, const std::vector<double>& replicates,
                     bool bootstrapped, double z) {
  Estimate e;
  e.value = value;
  e.se_wald = se_wald;
  e.se_bootstrap = kNaN;
  double se = se_wald;
  e.interval = "wald";
  if (bootstrapped && replicates.size() >= 2) {
    e.se_bootstrap =
        (percentile(replicates, 0.841344746) - percentile(replicates, 0.158655254)) / 2;
    if (e.se_bootstrap > se) {
      se = e.se_bootstrap;
      e.interval = "bootstrap";
    }
  }
  e.ci_low = value - z * se;
  e.ci_high = value + z * se;
  return e;
}

// The share of parameter vectors in which each variant has the top worth.
std::vector<double> favourite_shares(const Layout& layout,
                                     const std::vector<Eigen::VectorXd>& thetas) {
  std::vector<double> shares(std::size_t(layout.variants), 0.0);
  for (const Eigen::VectorXd& theta : thetas) {
    int best = layout.reference;
    double best_worth = 0;
    for (int v = 0; v < layout.variants; ++v) {
      const int k = layout.worth_index(v);
      const double worth = k < 0 ? 0.0 : theta(k);
      if (worth > best_worth) best = v, best_worth = worth;
    }
    shares[std::size_t(best)] += 1.0 / double(thetas.size());
  }
  return shares;
}

// The worths' covariance over every variant (the reference's row and column 0).
Eigen::MatrixXd worth_covariance(const Layout& layout, const Eigen::MatrixXd& covariance) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(layout.variants, layout.variants);
  for (int v = 0; v < layout.variants; ++v)
    for (int w = 0; w < layout.variants; ++w) {
      const int k = layout.worth_index(v), l = layout.worth_index(w);
      if (k >= 0 && l >= 0) out(v, w) = covariance(k, l);
    }
  return out;
}

// The variances of the worths' differences the intervals use: Wald's, or the larger of
// Wald's and the bootstrap's (robust: half the central 68.27 % range, squared) per pair.
Eigen::MatrixXd difference_variances(const Layout& layout, const Eigen::MatrixXd& covariance,
                                     const std::vector<Eigen::VectorXd>& replicates) {
  Eigen::MatrixXd v = statistics::pairwise_variances(worth_covariance(layout, covariance));
  if (replicates.size() < 2) return v;
  auto worth = [&](const Eigen::VectorXd& theta, int variant) {
    const int k = layout.worth_index(variant);
    return k < 0 ? 0.0 : theta(k);
  };
  for (int i = 0; i < layout.variants; ++i) {
    for (int j = i + 1; j < layout.variants; ++j) {
      std::vector<double> differences;
      for (const Eigen::VectorXd& r : replicates) differences.push_back(worth(r, i) - worth(r, j));
      const double se =
          (percentile(differences, 0.841344746) - percentile(differences, 0.158655254)) / 2;
      v(i, j) = v(j, i) = std::max(v(i, j), se * se);
    }
  }
  return v;
}

void add_quasi_variances(const Layout& layout, const Eigen::MatrixXd& covariance,
                         const std::vector<Eigen::VectorXd>& replicates, double z,
                         PreferenceScale& scale) {
  const auto qv = statistics::quasi_variances(difference_variances(layout, covariance, replicates));
  scale.quasi_variance_error = qv ? qv->worst_relative_error : kNaN;
  scale.quasi_variance_source =
      replicates.size() >= 2 ? "larger of wald and bootstrap, per pair" : "wald";
  for (int v = 0; v < layout.variants; ++v) {
    VariantWorth& w = scale.worths[std::size_t(v)];
    w.quasi_variance = qv ? qv->variances[std::size_t(v)] : kNaN;
    const double half = z / std::sqrt(2.0) * std::sqrt(w.quasi_variance);
    w.comparison_low = w.worth.value - half;
    w.comparison_high = w.worth.value + half;
  }
  if (!qv && layout.variants >= 3)
    scale.notes.push_back("no quasi-variances: their fit did not converge");
}

void count_answers(const PairData& data, PreferenceScale& scale) {
  for (const PairTrial& t : data.trials) {
    VariantWorth& first = scale.worths[std::size_t(t.first)];
    VariantWorth& second = scale.worths[std::size_t(t.second)];
    if (t.answer == 1) ++first.wins, ++second.losses;
    if (t.answer == 2) ++second.wins, ++first.losses;
    if (t.answer == 0) ++first.ties, ++second.ties;
  }
}

}  // namespace

PreferenceScale fit_preference_scale(const PairData& data, const PreferenceOptions& options,
                                     const std::function<void(int, int)>& progress) {
  if (const std::string problem = options.validate(); !problem.empty())
    throw std::invalid_argument("preference options: " + problem);
  if (data.variants.size() < 2)
    throw PreferenceScaleError("preference trials compare fewer than two variants");
  const Layout layout{int(data.variants.size()), reference_index(data, options),
                      options.order_effect && data.has_both_orders(), data.has_ties()};
  const auto point = newton(layout, cells_of(data, std::vector<int>(data.participants.size(), 1)));
  if (!point) throw PreferenceScaleError(separation_message(data));
  const Eigen::VectorXd& theta = point->first;
  const Evaluation e =
      evaluate(layout, cells_of(data, std::vector<int>(data.participants.size(), 1)), theta);
  const Eigen::MatrixXd covariance = e.information.inverse();

  PreferenceScale scale;
  scale.log_likelihood = e.log_likelihood;
  scale.iterations = point->second;
  scale.trials = int(data.trials.size());
  scale.participants = int(data.participants.size());
  const bool bootstrapped =
      options.bootstrap_replicates > 0 && scale.participants >= options.min_bootstrap_participants;
  Replicates replicates;
  if (bootstrapped) replicates = bootstrap(data, layout, options, progress);
  scale.replicates_used = int(replicates.thetas.size());
  scale.replicates_failed = replicates.failed;
  const bool use_bootstrap = bootstrapped && scale.replicates_used >= 2;
  const boost::math::normal normal;
  const double z = boost::math::quantile(normal, (1 + options.confidence) / 2);
  auto estimate = [&](int k) {
    std::vector<double> values;
    for (const Eigen::VectorXd& r : replicates.thetas) values.push_back(r(k));
    return estimate_of(theta(k), std::sqrt(covariance(k, k)), values, use_bootstrap, z);
  };
  const std::vector<Eigen::VectorXd> favourite_thetas =
      use_bootstrap ? replicates.thetas : normal_draws(theta, covariance, options.seed, 4000);
  scale.favourite_source =
      use_bootstrap ? "participant bootstrap" : "normal draws from the Wald covariance";
  const std::vector<double> shares = favourite_shares(layout, favourite_thetas);
  for (int v = 0; v < layout.variants; ++v) {
    VariantWorth worth;
    worth.variant = data.variants[std::size_t(v)];
    const int k = layout.worth_index(v);
    if (k < 0) {
      worth.worth.interval = "reference";
      worth.worth.se_bootstrap = kNaN;
    } else {
      worth.worth = estimate(k);
    }
    worth.p_favourite = shares[std::size_t(v)];
    scale.worths.push_back(worth);
  }
  count_answers(data, scale);
  add_quasi_variances(layout, covariance,
                      use_bootstrap ? replicates.thetas : std::vector<Eigen::VectorXd>{}, z, scale);
  if (layout.order) scale.order = estimate(layout.order_index());
  if (layout.ties) {
    Estimate log_nu = estimate(layout.nu_index());
    log_nu.value = std::exp(log_nu.value);
    log_nu.ci_low = std::exp(log_nu.ci_low);
    log_nu.ci_high = std::exp(log_nu.ci_high);
    scale.nu = log_nu;  // se_wald and se_bootstrap stay on the log scale
  }
  if (!layout.order)
    scale.notes.push_back("no pair was presented in both orders: no order effect fitted");
  if (options.bootstrap_replicates == 0)
    scale.notes.push_back(
        "Wald intervals: no participant bootstrap was asked for (--bootstrap 0), "
        "so the intervals assume the participants agree");
  else if (!bootstrapped)
    scale.notes.push_back("Wald intervals: " + std::to_string(scale.participants) +
                          " participants, fewer than the " +
                          std::to_string(options.min_bootstrap_participants) +
                          " a participant bootstrap needs; they assume the participants agree");
  if (layout.variants == 2)
    scale.notes.push_back(
        "no comparison intervals: with two variants the interval of the "
        "second against the reference is the comparison");
  if (replicates.failed > 0)
    scale.notes.push_back(std::to_string(replicates.failed) +
                          " bootstrap resamples had a variant that never won or never lost and "
                          "were left out");
  return scale;
}

namespace {}  // namespace

nlohmann::json preference_scale_json(const PreferenceScale& scale) {
  nlohmann::json out = nlohmann::json::object();
  nlohmann::json worths = nlohmann::json::array();
  for (const VariantWorth& w : scale.worths) {
    worths.push_back({{"variant", w.variant},
                      {"worth", w.worth.value},
                      {"ci_low", w.worth.ci_low},
                      {"ci_high", w.worth.ci_high},
                      {"se_wald", w.worth.se_wald},
                      {"se_bootstrap", json_number(w.worth.se_bootstrap)},
                      {"interval", w.worth.interval},
                      {"quasi_variance", json_number(w.quasi_variance)},
                      {"quasi_se", json_number(std::sqrt(w.quasi_variance))},
                      {"comparison_low", json_number(w.comparison_low)},
                      {"comparison_high", json_number(w.comparison_high)},
                      {"p_favourite", w.p_favourite},
                      {"wins", w.wins},
                      {"losses", w.losses},
                      {"ties", w.ties}});
  }
  out["preference_scale"] = worths;
  if (scale.nu) {
    out["ties"] = {{"nu", scale.nu->value},
                   {"ci_low", scale.nu->ci_low},
                   {"ci_high", scale.nu->ci_high},
                   {"interval", scale.nu->interval}};
  }
  if (scale.order) {
    out["order_effect"] = {{"delta", scale.order->value},
                           {"ci_low", scale.order->ci_low},
                           {"ci_high", scale.order->ci_high},
                           {"interval", scale.order->interval}};
  }
  out["preference_fit"] = {{"trials", scale.trials},
                           {"participants", scale.participants},
                           {"log_likelihood", scale.log_likelihood},
                           {"iterations", scale.iterations},
                           {"bootstrap_replicates_used", scale.replicates_used},
                           {"bootstrap_replicates_failed", scale.replicates_failed},
                           {"favourite_from", scale.favourite_source},
                           {"quasi_variance_worst_error", json_number(scale.quasi_variance_error)},
                           {"quasi_variance_from", scale.quasi_variance_source},
                           {"notes", scale.notes}};
  return out;
}

}  // namespace doorbench::study
