#include "study/statistics/thresholds.h"

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>
#include <boost/math/distributions/students_t.hpp>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <set>
#include <stdexcept>

#include "acquisition/session/output_file.h"
#include "analysis/report/svg_charts.h"
#include "core/json_number.h"
#include "core/number_format.h"
#include "study/question.h"
#include "study/statistics/psychometric_likelihood.h"

namespace doorbench::study {
namespace {

using statistics::psychometric_cdf_pair;
using statistics::psychometric_z;
using statistics::quantile_above_median;

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
    const auto [f, not_f] =
        psychometric_cdf_pair(shape, psychometric_z(shape, t.level, pse, spread));
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
  const auto [f, not_f] = psychometric_cdf_pair(shape, psychometric_z(shape, level, pse, spread));
  (void)not_f;
  return lapse / 2.0 + (1.0 - lapse) * f;
}

CurvePoint PsychometricFit::curve_point(double level, double confidence) const {
  const statistics::PsychometricLayout layout{pse_fitted, max_lapse > 0.0, max_lapse};
  const statistics::PsychometricValues values{pse, std::log(spread), lapse};
  const double z = boost::math::quantile(boost::math::normal(), 0.5 + confidence / 2.0);
  return statistics::psychometric_curve_point(
      shape, values, layout, Eigen::Map<const Eigen::Matrix3d>(covariance.data()), level, z);
}

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
  statistics::PsychometricProblem problem{statistics::count_levels(trials), options.shape, {}};
  // Levels all on one side of the reference (a staircase): the PSE is the reference.
  problem.layout.fit_pse = *levels.begin() < 0.0 && *levels.rbegin() > 0.0;
  problem.layout.fit_lapse = options.max_lapse > 0.0;
  problem.layout.max_lapse = options.max_lapse;
  const double range = std::max(*levels.rbegin() - *levels.begin(), std::abs(*levels.rbegin()));
  const auto best = statistics::fit_psychometric_free(problem, range);
  const statistics::PsychometricValues v = statistics::unpack(best.x, problem.layout);
  PsychometricFit fit;
  fit.max_lapse = options.max_lapse;
  fit.pse_fitted = problem.layout.fit_pse;
  const Eigen::Matrix3d covariance = statistics::psychometric_covariance(problem, best.x);
  std::copy(covariance.data(), covariance.data() + 9, fit.covariance.begin());
  fit.shape = options.shape;
  fit.pse = v.pse;
  fit.spread = std::exp(v.log_spread);
  fit.lapse = v.lapse;
  fit.log_likelihood = -best.value;
  fit.trials = static_cast<int>(trials.size());
  fit.converged = best.converged;
  fit.weber_fraction = weber_fraction(options.shape, fit.spread, options.criterion);
  const double cut = 0.5 * boost::math::quantile(boost::math::chi_squared(1.0), options.confidence);
  const double low = statistics::profile_limit(problem, best.x, best.value, cut, -1);
  const double high = statistics::profile_limit(problem, best.x, best.value, cut, +1);
  fit.ci_low =
      std::isfinite(low) ? weber_fraction(options.shape, std::exp(low), options.criterion) : 0.0;
  fit.ci_high = std::isfinite(high)
                    ? weber_fraction(options.shape, std::exp(high), options.criterion)
                    : std::numeric_limits<double>::infinity();
  return fit;
}

namespace {

// The staircase's moves: whether they follow an up-down rule, its N, and the reversal levels.
struct StaircaseMoves {
  bool consistent = true;
  int down_rule = 0;                    // 0 when no step down was seen
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
      if (direction < 0)
        moves.down_rule = moves.down_rule == 0 ? run : std::min(moves.down_rule, run);
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
                                                      const ThresholdOptions& options,
                                                      bool forced) {
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
  const double t =
      boost::math::quantile(boost::math::students_t(k - 1.0), 0.5 + options.confidence / 2.0);
  out.weber_fraction = std::expm1(mean);
  out.ci_low = std::expm1(mean - t * sd / std::sqrt(k));
  out.ci_high = std::expm1(mean + t * sd / std::sqrt(k));
  std::set<double> levels;
  for (const auto& trial : trials) levels.insert(trial.level);
  if (trials.size() >= 3 && levels.size() >= 2) out.fit = fit_psychometric(trials, options);
  return out;
}

namespace {

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
    auto it =
        std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == key; });
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
  out.counts = statistics::count_levels(trials);
  const double low = out.counts.front().level, high = out.counts.back().level;
  for (int i = 0; i <= 100; ++i)
    out.curve.push_back(out.panel.curve_point(low + (high - low) * i / 100.0, options.confidence));
  using Id = std::string;
  for (auto& [participant, own] :
       group_by<Id>(trials, [](const StrongerObservation& t) { return t.participant; })) {
    if (options.per_participant && fittable(own)) {
      out.participants.emplace_back(participant, fit_psychometric(own, options));
    }
    for (auto& [block, run] :
         group_by<Id>(own, [](const StrongerObservation& t) { return t.block; })) {
      std::stable_sort(run.begin(), run.end(),
                       [](const auto& a, const auto& b) { return a.trial < b.trial; });
      const bool forced =
          std::find(options.staircase_blocks.begin(), options.staircase_blocks.end(), block) !=
          options.staircase_blocks.end();
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

nlohmann::json fit_row(const ParameterThresholds& p, const std::string& participant,
                       const PsychometricFit& fit, double criterion, const std::string& method) {
  return {{"parameter", p.parameter},
          {"reference", p.reference},
          {"participant", participant},
          {"method", method},
          {"weber_fraction", fit.weber_fraction},
          {"ci_low", json_number(fit.ci_low)},
          {"ci_high", json_number(fit.ci_high)},
          {"criterion",
           format_percent(criterion, 1) + " of the lapse-free " +
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
                      {"criterion", format_percent(s.target, 1) + " correct (1-up-" +
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
    if (spelled_kind(question) != QuestionKind::kStronger) continue;
    const int line = table.line_numbers[r];
    const std::optional<Question> asked = Question::parse(question);
    if (!asked)
      throw TrialsTableError(table.source, line, "question 'stronger:' names no parameter");
    const std::string& parameter = asked->subject;
    const std::string& answer = table.value(r, "answer");
    if (answer != "1" && answer != "2") {
      throw TrialsTableError(table.source, line,
                             "answer '" + answer + "' is not 1 or 2 (which felt stronger)");
    }
    int trial = static_cast<int>(r);
    const std::string& trial_text = table.value(r, "trial");
    std::from_chars(trial_text.data(), trial_text.data() + trial_text.size(), trial);
    rows.push_back({r, table.value(r, "participant"), table.value(r, "block"), parameter,
                    parse_label(table, r, "first", parameter),
                    parse_label(table, r, "second", parameter), answer == "2", trial});
  }
  // The reference of each participant's block: the label in every trial.
  std::map<std::pair<std::string, std::string>, std::vector<const StrongerRow*>> blocks;
  for (const StrongerRow& row : rows) blocks[{row.participant, row.block}].push_back(&row);
  std::map<std::pair<std::string, std::string>, Label> references;
  for (const auto& [key, members] : blocks) {
    std::optional<Label> best;
    for (const Label* candidate : {&members.front()->first, &members.front()->second}) {
      const bool everywhere =
          std::all_of(members.begin(), members.end(), [&](const StrongerRow* m) {
            return m->first.text == candidate->text || m->second.text == candidate->text;
          });
      if (everywhere &&
          (!best || std::abs(std::log(candidate->factor)) < std::abs(std::log(best->factor)))) {
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

DoseResponsePlot curve_plot(const ParameterThresholds& t) {
  if (t.counts.empty()) throw std::invalid_argument("psychometric plot: no data");
  DoseResponsePlot plot;
  plot.title = "Which felt stronger: " + t.parameter + " around " + t.reference;
  plot.x_label = "comparison / reference [1]";
  plot.y_label = "P(comparison felt stronger) [1]";
  for (const LevelCount& c : t.counts) {
    plot.x.push_back(std::exp(c.level));
    plot.y.push_back(static_cast<double>(c.stronger) / c.trials);
    plot.weight.push_back(c.trials);
  }
  plot.points_label = "the panel's answers (area: trials)";
  plot.curve_label = "fit (JND " + format_percent(t.panel.weber_fraction, 1) + ")";
  if (!t.curve.empty()) {
    for (const CurvePoint& c : t.curve) {
      plot.curve_x.push_back(std::exp(c.level));
      plot.curve_y.push_back(c.p);
      plot.band_low.push_back(c.low);
      plot.band_high.push_back(c.high);
    }
    plot.band_label = "95 % band of the fit";
    return plot;
  }
  // Without the band (an analysis.json written before it): the curve alone.
  const double low = t.counts.front().level, high = t.counts.back().level;
  for (int i = 0; i <= 100; ++i) {
    const double level = low + (high - low) * i / 100.0;
    plot.curve_x.push_back(std::exp(level));
    plot.curve_y.push_back(t.panel.probability(level));
  }
  return plot;
}

}  // namespace

std::string render_psychometric_plot(const ParameterThresholds& thresholds) {
  return render_svg_dose_response(curve_plot(thresholds));
}

void write_psychometric_plot(const std::string& path, const ParameterThresholds& thresholds) {
  write_text_file_atomically(path, render_psychometric_plot(thresholds));
}

}  // namespace doorbench::study
