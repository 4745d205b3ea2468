#include "study/statistics/thresholds.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <map>
#include <set>
#include <stdexcept>

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>

#include "analysis/report/svg_plot.h"
#include "study/statistics/numeric_minimize.h"
#include "study/statistics/logistic.h"

namespace doorbench::study {
namespace {

// F(z) and 1 - F(z), each computed directly so that neither tail loses digits.
std::pair<double, double> cdf_pair(PsychometricShape shape, double z) {
  if (shape == PsychometricShape::kCumulativeNormal) {
    return {0.5 * std::erfc(-z / std::numbers::sqrt2), 0.5 * std::erfc(z / std::numbers::sqrt2)};
  }
  const double e = std::exp(z);
  return {-std::expm1(-e), std::exp(-e)};
}

// The lapse-free F's quantile in units of spread, relative to its median.
double quantile_above_median(PsychometricShape shape, double p) {
  if (shape == PsychometricShape::kCumulativeNormal) {
    return boost::math::quantile(boost::math::normal(), p);
  }
  return std::log(-std::log1p(-p)) - std::log(std::log(2.0));
}

// Gumbel's median is at z = ln ln 2; the "pse" parameter is the median, so shift z by it.
double z_of(PsychometricShape shape, double level, double pse, double spread) {
  const double z = (level - pse) / spread;
  return shape == PsychometricShape::kWeibull ? z + std::log(std::log(2.0)) : z;
}


// The free parameters: [pse unless fixed, ln spread, lapse logit unless max_lapse = 0].
struct PsychometricLayout {
  bool fit_pse = true;
  bool fit_lapse = true;
  double max_lapse = 0.1;
  int size() const { return 1 + (fit_pse ? 1 : 0) + (fit_lapse ? 1 : 0); }
};

struct Values {
  double pse = 0.0, log_spread = 0.0, lapse = 0.0;
};

Values unpack(const Eigen::VectorXd& x, const PsychometricLayout& layout) {
  Values v;
  int i = 0;
  if (layout.fit_pse) v.pse = x[i++];
  v.log_spread = x[i++];
  if (layout.fit_lapse) v.lapse = layout.max_lapse * logistic(x[i]);
  return v;
}

int spread_index(const PsychometricLayout& layout) { return layout.fit_pse ? 1 : 0; }

}  // namespace

std::string ThresholdOptions::validate() const {
  if (!(max_lapse >= 0.0 && max_lapse < 0.5)) return "max_lapse must be in [0, 0.5)";
  if (!(criterion > 0.5 && criterion < 1.0)) return "criterion must be in (0.5, 1)";
  if (!(confidence > 0.0 && confidence < 1.0)) return "confidence must be in (0, 1)";
  if (staircase_reversals < 2) return "staircase_reversals must be at least 2";
  return "";
}

double psychometric_log_likelihood(std::span<const StrongerObservation> trials,
                                   PsychometricShape shape, double pse, double spread,
                                   double lapse) {
  double total = 0.0;
  for (const StrongerObservation& t : trials) {
    const auto [f, not_f] = cdf_pair(shape, z_of(shape, t.level, pse, spread));
    const double p = t.comparison_stronger ? lapse / 2.0 + (1.0 - lapse) * f
                                           : lapse / 2.0 + (1.0 - lapse) * not_f;
    total += std::log(p);
  }
  return total;
}

double weber_fraction(PsychometricShape shape, double spread, double criterion) {
  return std::expm1(spread * quantile_above_median(shape, criterion));
}

double PsychometricFit::probability(double level) const {
  const auto [f, not_f] = cdf_pair(shape, z_of(shape, level, pse, spread));
  (void)not_f;
  return lapse / 2.0 + (1.0 - lapse) * f;
}

namespace {

struct Problem {
  std::span<const StrongerObservation> trials;
  PsychometricShape shape;
  PsychometricLayout layout;
};

double negative_log_likelihood(const Problem& problem, const Eigen::VectorXd& x) {
  const Values v = unpack(x, problem.layout);
  if (v.log_spread < -30.0 || v.log_spread > 30.0) return std::numeric_limits<double>::infinity();
  const double value = psychometric_log_likelihood(problem.trials, problem.shape, v.pse,
                                                   std::exp(v.log_spread), v.lapse);
  return std::isfinite(value) ? -value : std::numeric_limits<double>::infinity();
}

// The best of a few starts.
statistics::MinimizeResult fit_free(const Problem& problem, double level_range) {
  statistics::MinimizeResult best;
  best.value = std::numeric_limits<double>::infinity();
  const statistics::Objective f = [&](const Eigen::VectorXd& x) {
    return negative_log_likelihood(problem, x);
  };
  for (const double spread : {0.1 * level_range, 0.5 * level_range, 2.0 * level_range}) {
    Eigen::VectorXd x0(problem.layout.size());
    int i = 0;
    if (problem.layout.fit_pse) x0[i++] = 0.0;
    x0[i++] = std::log(spread);
    if (problem.layout.fit_lapse) x0[i] = std::log(0.02 / (problem.layout.max_lapse - 0.02));
    if (!std::isfinite(f(x0))) continue;
    auto result = statistics::minimize(f, x0);
    if (result.value < best.value) best = result;
  }
  if (!std::isfinite(best.value)) throw std::invalid_argument("no start value has a finite likelihood");
  return best;
}

// Profile negative log-likelihood at a fixed ln spread, warm-started from `start`
// (the other parameters), which it updates.
double profile(const Problem& problem, double log_spread, Eigen::VectorXd& others) {
  const int s = spread_index(problem.layout);
  const auto full = [&](const Eigen::VectorXd& o) {
    Eigen::VectorXd x(o.size() + 1);
    for (int i = 0, j = 0; i < x.size(); ++i) x[i] = i == s ? log_spread : o[j++];
    return x;
  };
  if (others.size() == 0) return negative_log_likelihood(problem, full(others));
  const statistics::Objective f = [&](const Eigen::VectorXd& o) {
    return negative_log_likelihood(problem, full(o));
  };
  if (!std::isfinite(f(others))) others.setZero();
  auto result = statistics::minimize(f, others);
  if (problem.layout.fit_lapse) {
    // A lapse rate driven to 0 saturates its logistic, where Newton steps stall: also start
    // from a lapse of 2 % and keep the better.
    Eigen::VectorXd reset = result.x;
    reset[reset.size() - 1] = std::log(0.02 / (problem.layout.max_lapse - 0.02));
    if (std::isfinite(f(reset))) {
      auto second = statistics::minimize(f, reset);
      if (second.value < result.value) result = std::move(second);
    }
  }
  others = result.x;
  return result.value;
}

// Where the profile rises by `cut` above its minimum, going from the optimum in `direction`
// (+1 / -1) in ln spread; +-infinity when it does not within 12 units.
double profile_limit(const Problem& problem, const Eigen::VectorXd& optimum, double minimum,
                     double cut, int direction) {
  const int s = spread_index(problem.layout);
  Eigen::VectorXd others(optimum.size() - 1);
  for (int i = 0, j = 0; i < optimum.size(); ++i) {
    if (i != s) others[j++] = optimum[i];
  }
  const double centre = optimum[s];
  double inside = centre, outside = centre;
  bool crossed = false;
  Eigen::VectorXd warm = others;
  for (double distance = 0.1; distance <= 12.0; distance *= 1.5) {
    outside = centre + direction * distance;
    if (profile(problem, outside, warm) - minimum > cut) {
      crossed = true;
      break;
    }
    inside = outside;
  }
  if (!crossed) return direction * std::numeric_limits<double>::infinity();
  for (int iteration = 0; iteration < 40 && std::abs(outside - inside) > 1e-5; ++iteration) {
    const double middle = 0.5 * (inside + outside);
    Eigen::VectorXd start = others;
    (profile(problem, middle, start) - minimum > cut ? outside : inside) = middle;
  }
  return 0.5 * (inside + outside);
}

}  // namespace

PsychometricFit fit_psychometric(std::span<const StrongerObservation> trials,
                                 const ThresholdOptions& options) {
  if (const std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument("thresholds: " + problem);
  }
  std::set<double> levels;
  for (const auto& t : trials) levels.insert(t.level);
  if (trials.size() < 3 || levels.size() < 2) {
    throw std::invalid_argument("thresholds: fewer than 3 trials or 2 levels to fit");
  }
  Problem problem{trials, options.shape, {}};
  // Levels all on one side of the reference (a staircase): the PSE is the reference.
  problem.layout.fit_pse = *levels.begin() < 0.0 && *levels.rbegin() > 0.0;
  problem.layout.fit_lapse = options.max_lapse > 0.0;
  problem.layout.max_lapse = options.max_lapse;
  const double range = std::max(*levels.rbegin() - *levels.begin(), std::abs(*levels.rbegin()));
  const auto best = fit_free(problem, range);
  const Values v = unpack(best.x, problem.layout);
  PsychometricFit fit;
  fit.shape = options.shape;
  fit.pse = v.pse;
  fit.spread = std::exp(v.log_spread);
  fit.lapse = v.lapse;
  fit.log_likelihood = -best.value;
  fit.trials = static_cast<int>(trials.size());
  fit.converged = best.converged;
  fit.weber_fraction = weber_fraction(options.shape, fit.spread, options.criterion);
  const double cut =
      0.5 * boost::math::quantile(boost::math::chi_squared(1.0), options.confidence);
  const double low = profile_limit(problem, best.x, best.value, cut, -1);
  const double high = profile_limit(problem, best.x, best.value, cut, +1);
  fit.ci_low = std::isfinite(low) ? weber_fraction(options.shape, std::exp(low), options.criterion) : 0.0;
  fit.ci_high = std::isfinite(high) ? weber_fraction(options.shape, std::exp(high), options.criterion)
                                    : std::numeric_limits<double>::infinity();
  return fit;
}

namespace {

// The staircase's moves: whether they follow an up-down rule, its N, and the reversal levels.
struct StaircaseMoves {
  bool consistent = true;
  int down_rule = 0;  // 0 when no step down was seen
  std::vector<double> reversal_levels;  // |ln ratio| where the direction turned
};

StaircaseMoves read_moves(std::span<const StrongerObservation> trials) {
  StaircaseMoves moves;
  int previous_direction = 0;
  int run = 0;  // consecutive "correct" answers at the current level
  for (std::size_t t = 0; t < trials.size(); ++t) {
    const double magnitude = std::abs(trials[t].level);
    if (t > 0) {
      const double before = std::abs(trials[t - 1].level);
      const int direction = magnitude < before ? -1 : magnitude > before ? 1 : 0;
      const bool correct_before = trials[t - 1].comparison_stronger == (trials[t - 1].level > 0.0);
      if ((direction < 0 && !correct_before) || (direction > 0 && correct_before)) {
        moves.consistent = false;
      }
      if (direction < 0) moves.down_rule = moves.down_rule == 0 ? run : std::min(moves.down_rule, run);
      if (direction != 0) {
        if (previous_direction != 0 && direction != previous_direction) {
          moves.reversal_levels.push_back(before);
        }
        previous_direction = direction;
        run = 0;
      }
    }
    const bool correct = trials[t].comparison_stronger == (trials[t].level > 0.0);
    run = correct ? run + 1 : 0;
  }
  if (previous_direction == 0) moves.consistent = false;
  return moves;
}

}  // namespace

std::optional<StaircaseThreshold> staircase_threshold(std::span<const StrongerObservation> trials,
                                                      const ThresholdOptions& options, bool forced) {
  if (trials.empty()) return std::nullopt;
  bool one_side = true;
  for (const auto& t : trials) {
    if (t.level == 0.0 || (t.level > 0.0) != (trials.front().level > 0.0)) one_side = false;
  }
  const StaircaseMoves moves = read_moves(trials);
  if (!forced && (!one_side || !moves.consistent)) return std::nullopt;
  if (moves.reversal_levels.size() < 2) return std::nullopt;
  StaircaseThreshold out;
  out.participant = trials.front().participant;
  out.block = trials.front().block;
  out.down_rule = std::max(moves.down_rule, 1);
  out.target = std::pow(0.5, 1.0 / out.down_rule);
  out.reversals_total = static_cast<int>(moves.reversal_levels.size());
  const int k = std::min(options.staircase_reversals, out.reversals_total);
  out.reversals_used = k;
  double sum = 0.0, squares = 0.0;
  for (int i = out.reversals_total - k; i < out.reversals_total; ++i) {
    sum += moves.reversal_levels[i];
    squares += moves.reversal_levels[i] * moves.reversal_levels[i];
  }
  const double mean = sum / k;
  const double sd = std::sqrt(std::max(0.0, (squares - k * mean * mean) / (k - 1)));
  const double t = boost::math::quantile(boost::math::students_t(k - 1.0),
                                         0.5 + options.confidence / 2.0);
  out.weber_fraction = std::expm1(mean);
  out.ci_low = std::expm1(mean - t * sd / std::sqrt(k));
  out.ci_high = std::expm1(mean + t * sd / std::sqrt(k));
  std::set<double> levels;
  for (const auto& trial : trials) levels.insert(trial.level);
  if (trials.size() >= 3 && levels.size() >= 2) out.fit = fit_psychometric(trials, options);
  return out;
}

namespace {

std::vector<LevelCount> count_levels(std::span<const StrongerObservation> trials) {
  std::map<double, LevelCount> by_level;
  for (const auto& t : trials) {
    LevelCount& c = by_level[t.level];
    c.level = t.level;
    ++c.trials;
    c.stronger += t.comparison_stronger ? 1 : 0;
  }
  std::vector<LevelCount> out;
  for (const auto& [level, count] : by_level) out.push_back(count);
  return out;
}

bool fittable(std::span<const StrongerObservation> trials) {
  std::set<double> levels;
  for (const auto& t : trials) levels.insert(t.level);
  return trials.size() >= 3 && levels.size() >= 2;
}

// Groups in order of first appearance.
template <typename Key, typename KeyOf>
std::vector<std::pair<Key, std::vector<StrongerObservation>>> group_by(
    std::span<const StrongerObservation> trials, KeyOf key_of) {
  std::vector<std::pair<Key, std::vector<StrongerObservation>>> groups;
  for (const auto& t : trials) {
    const Key key = key_of(t);
    auto it = std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == key; });
    if (it == groups.end()) it = groups.insert(groups.end(), {key, {}});
    it->second.push_back(t);
  }
  return groups;
}

ParameterThresholds fit_parameter(const std::string& parameter, const std::string& reference,
                                  std::vector<StrongerObservation> trials,
                                  const ThresholdOptions& options) {
  ParameterThresholds out;
  out.parameter = parameter;
  out.reference = reference;
  if (!fittable(trials)) {
    throw std::invalid_argument("thresholds of " + parameter + " around " + reference +
                                ": fewer than 3 trials or 2 levels to fit");
  }
  out.panel = fit_psychometric(trials, options);
  out.counts = count_levels(trials);
  using Id = std::string;
  for (auto& [participant, own] :
       group_by<Id>(trials, [](const StrongerObservation& t) { return t.participant; })) {
    if (options.per_participant && fittable(own)) {
      out.participants.emplace_back(participant, fit_psychometric(own, options));
    }
    for (auto& [block, run] : group_by<Id>(own, [](const StrongerObservation& t) { return t.block; })) {
      std::stable_sort(run.begin(), run.end(),
                       [](const auto& a, const auto& b) { return a.trial < b.trial; });
      const bool forced = std::find(options.staircase_blocks.begin(), options.staircase_blocks.end(),
                                    block) != options.staircase_blocks.end();
      if (auto staircase = staircase_threshold(run, options, forced)) {
        out.staircases.push_back(std::move(*staircase));
      }
    }
  }
  return out;
}

}  // namespace

ThresholdsResult fit_thresholds(std::span<const StrongerObservation> trials,
                                const ThresholdOptions& options) {
  if (const std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument("thresholds: " + problem);
  }
  ThresholdsResult result;
  result.criterion = options.criterion;
  using Key = std::pair<std::string, std::string>;
  for (auto& [key, group] : group_by<Key>(trials, [](const StrongerObservation& t) {
         return Key{t.parameter, t.reference};
       })) {
    result.parameters.push_back(fit_parameter(key.first, key.second, std::move(group), options));
  }
  return result;
}

namespace {

nlohmann::json number_or_null(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

std::string percent(double p) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f%%", 100.0 * p);
  return text;
}

nlohmann::json fit_row(const ParameterThresholds& p, const std::string& participant,
                       const PsychometricFit& fit, double criterion, const std::string& method) {
  return {{"parameter", p.parameter},
          {"reference", p.reference},
          {"participant", participant},
          {"method", method},
          {"weber_fraction", fit.weber_fraction},
          {"ci_low", number_or_null(fit.ci_low)},
          {"ci_high", number_or_null(fit.ci_high)},
          {"criterion", percent(criterion) + " of the lapse-free " +
                            (fit.shape == PsychometricShape::kWeibull ? "Weibull" : "cumulative normal") +
                            " above its PSE"},
          {"interval", "profile likelihood"},
          {"pse", fit.pse},
          {"spread", fit.spread},
          {"lapse", fit.lapse},
          {"trials", fit.trials}};
}

}  // namespace

nlohmann::json ThresholdsResult::to_json() const {
  nlohmann::json rows = nlohmann::json::array();
  for (const ParameterThresholds& p : parameters) {
    rows.push_back(fit_row(p, "panel", p.panel, criterion, "psychometric fit, pooled"));
    for (const auto& [participant, fit] : p.participants) {
      rows.push_back(fit_row(p, participant, fit, criterion, "psychometric fit"));
    }
    for (const StaircaseThreshold& s : p.staircases) {
      rows.push_back({{"parameter", p.parameter},
                      {"reference", p.reference},
                      {"participant", s.participant},
                      {"block", s.block},
                      {"method", "staircase reversals"},
                      {"weber_fraction", s.weber_fraction},
                      {"ci_low", s.ci_low},
                      {"ci_high", s.ci_high},
                      {"criterion", percent(s.target) + " correct (1-up-" +
                                        std::to_string(s.down_rule) + "-down, Levitt 1971)"},
                      {"interval", "t over the reversals"},
                      {"reversals", s.reversals_used},
                      {"down_rule", s.down_rule}});
      if (s.fit.trials > 0) {
        nlohmann::json row = fit_row(p, s.participant, s.fit, criterion, "staircase fit");
        row["block"] = s.block;
        rows.push_back(row);
      }
    }
  }
  return rows;
}

namespace {

struct Label {
  std::string text;
  double factor = 1.0;
};

Label parse_label(const TrialsTable& table, std::size_t row, std::string_view column,
                  const std::string& parameter) {
  const std::string& text = table.value(row, column);
  const std::size_t star = text.find('*');
  const std::string name = text.substr(0, star);
  Label label{text, 1.0};
  bool ok = name == parameter;
  if (ok && star != std::string::npos) {
    const char* begin = text.data() + star + 1;
    const char* end = text.data() + text.size();
    const auto [stop, error] = std::from_chars(begin, end, label.factor);
    ok = error == std::errc() && stop == end && begin != end && label.factor > 0.0 &&
         std::isfinite(label.factor);
  }
  if (!ok) {
    throw TrialsTableError(table.source, table.line_numbers[row],
                           std::string(column) + " '" + text + "' is not " + parameter + " or " +
                               parameter + "*FACTOR with a positive FACTOR");
  }
  return label;
}

struct StrongerRow {
  std::size_t row;
  std::string participant, block, parameter;
  Label first, second;
  bool second_stronger;
  int trial;
};

}  // namespace

std::vector<StrongerObservation> stronger_observations(const TrialsTable& table) {
  std::vector<StrongerRow> rows;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    const std::string& question = table.value(r, "question");
    if (!question.starts_with("stronger:")) continue;
    const std::string parameter = question.substr(9);
    const int line = table.line_numbers[r];
    if (parameter.empty()) throw TrialsTableError(table.source, line, "question 'stronger:' names no parameter");
    const std::string& answer = table.value(r, "answer");
    if (answer != "1" && answer != "2") {
      throw TrialsTableError(table.source, line, "answer '" + answer + "' is not 1 or 2 (which felt stronger)");
    }
    int trial = static_cast<int>(r);
    const std::string& trial_text = table.value(r, "trial");
    std::from_chars(trial_text.data(), trial_text.data() + trial_text.size(), trial);
    rows.push_back({r, table.value(r, "participant"), table.value(r, "block"), parameter,
                    parse_label(table, r, "first", parameter), parse_label(table, r, "second", parameter),
                    answer == "2", trial});
  }
  // The reference of each participant's block: the label in every trial.
  std::map<std::pair<std::string, std::string>, std::vector<const StrongerRow*>> blocks;
  for (const StrongerRow& row : rows) blocks[{row.participant, row.block}].push_back(&row);
  std::map<std::pair<std::string, std::string>, Label> references;
  for (const auto& [key, members] : blocks) {
    std::optional<Label> best;
    for (const Label* candidate : {&members.front()->first, &members.front()->second}) {
      const bool everywhere = std::all_of(members.begin(), members.end(), [&](const StrongerRow* m) {
        return m->first.text == candidate->text || m->second.text == candidate->text;
      });
      if (everywhere && (!best || std::abs(std::log(candidate->factor)) < std::abs(std::log(best->factor)))) {
        best = *candidate;
      }
    }
    if (!best) {
      throw TrialsTableError(table.source, table.line_numbers[members.front()->row],
                             "block '" + key.second + "' of participant '" + key.first +
                                 "': no variant is in every trial, so none is the reference");
    }
    references[key] = *best;
  }
  std::vector<StrongerObservation> out;
  for (const StrongerRow& row : rows) {
    const Label& reference = references[{row.participant, row.block}];
    const bool comparison_first = row.first.text != reference.text;
    const Label& comparison = comparison_first ? row.first : row.second;
    out.push_back({row.participant, row.block, row.trial, row.parameter, reference.text,
                   std::log(comparison.factor / reference.factor),
                   comparison_first ? !row.second_stronger : row.second_stronger});
  }
  return out;
}

namespace {

struct CurvePlot {
  PlotOptions options;
  std::vector<double> data_x, data_y, fit_x, fit_y;
  std::vector<PlotSeries> series;
};

void fill_curve_plot(CurvePlot& plot, const ParameterThresholds& t) {
  if (t.counts.empty()) throw std::invalid_argument("psychometric plot: no data");
  plot.options.title = "Which felt stronger: " + t.parameter + " around " + t.reference;
  plot.options.x_label = "comparison / reference [1]";
  plot.options.y_label = "P(comparison felt stronger) [1]";
  for (const LevelCount& c : t.counts) {
    plot.data_x.push_back(std::exp(c.level));
    plot.data_y.push_back(static_cast<double>(c.stronger) / c.trials);
  }
  const double low = t.counts.front().level, high = t.counts.back().level;
  for (int i = 0; i <= 200; ++i) {
    const double level = low + (high - low) * i / 200.0;
    plot.fit_x.push_back(std::exp(level));
    plot.fit_y.push_back(t.panel.probability(level));
  }
  plot.series.push_back({"panel's answers", plot.data_x, plot.data_y, "", plot_style::Meaning::kMeasured});
  plot.series.push_back({"fit (JND " + percent(t.panel.weber_fraction) + ")", plot.fit_x, plot.fit_y, "",
                         plot_style::Meaning::kSimulated});
}

}  // namespace

std::string render_psychometric_plot(const ParameterThresholds& thresholds) {
  CurvePlot plot;
  fill_curve_plot(plot, thresholds);
  return render_svg_plot(plot.options, plot.series);
}

void write_psychometric_plot(const std::string& path, const ParameterThresholds& thresholds) {
  CurvePlot plot;
  fill_curve_plot(plot, thresholds);
  write_svg_plot(path, plot.options, plot.series);
}

}  // namespace doorbench::study
