#include "study/statistics/tuning.h"

#include <algorithm>
#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <stdexcept>

#include "analysis/model/parameter_file.h"
#include "analysis/model/physical_model.h"
#include "analysis/model/sensory_model.h"
#include "analysis/report/svg_plot.h"
#include "core/json_number.h"
#include "study/question.h"

namespace doorbench::study {

std::string TuningOptions::validate() const {
  if (!(confidence > 0.0 && confidence < 1.0)) return "confidence must be in (0, 1)";
  if (min_cluster_size < 1) return "min_cluster_size must be at least 1";
  if (!(min_separation_steps >= 0.0)) return "min_separation_steps must be at least 0";
  for (const auto& [name, w] : measured_weber) {
    if (!(w > 0.0) || !std::isfinite(w)) return "measured_weber of " + name + " must be positive";
  }
  return "";
}

std::optional<std::pair<double, std::string>> typical_weber_fraction(const std::string& parameter) {
  static const std::set<std::string> inertia{"J", "J_d", "m_d"};
  static const std::set<std::string> stiffness{"k",   "k_inf", "k_lock", "k_stop",
                                               "k_s", "k_l",   "k_seal"};
  static const std::set<std::string> viscosity{"c", "c_stop", "b_h"};
  static const std::set<std::string> friction{"d1", "d2", "T_h", "mu_g", "mu_l"};
  if (inertia.contains(parameter)) return std::pair{0.10, std::string("typical: inertia 10%")};
  if (stiffness.contains(parameter)) return std::pair{0.15, std::string("typical: stiffness 15%")};
  if (viscosity.contains(parameter)) return std::pair{0.20, std::string("typical: viscosity 20%")};
  if (friction.contains(parameter)) return std::pair{0.20, std::string("typical: friction 20%")};
  return std::nullopt;
}

std::map<std::string, double> measured_weber_fractions(const ThresholdsResult& thresholds) {
  std::map<std::string, double> out;
  for (const ParameterThresholds& p : thresholds.parameters) {
    if (!out.contains(p.parameter)) out[p.parameter] = p.panel.weber_fraction;
  }
  return out;
}

namespace {

ParameterDistribution describe(const std::string& name, const std::vector<double>& values,
                               const TuningOptions& options) {
  ParameterDistribution d;
  d.parameter = name;
  d.doors = static_cast<int>(values.size());
  d.min = *std::min_element(values.begin(), values.end());
  d.max = *std::max_element(values.begin(), values.end());
  d.log_scale = d.min > 0.0;
  std::vector<double> x = values;
  if (d.log_scale) {
    for (double& v : x) v = std::log(v);
  }
  const double n = static_cast<double>(x.size());
  double mean = 0.0;
  for (const double v : x) mean += v / n;
  double squares = 0.0;
  for (const double v : x) squares += (v - mean) * (v - mean);
  d.spread = x.size() > 1 ? std::sqrt(squares / (n - 1.0)) : 0.0;
  const double t = x.size() > 1 ? boost::math::quantile(boost::math::students_t(n - 1.0),
                                                        0.5 + options.confidence / 2.0)
                                : std::numeric_limits<double>::infinity();
  const double half =
      x.size() > 1 ? t * d.spread / std::sqrt(n) : std::numeric_limits<double>::infinity();
  const auto back = [&](double v) { return d.log_scale ? std::exp(v) : v; };
  d.centre = back(mean);
  d.ci_low = back(mean - half);
  d.ci_high = back(mean + half);
  if (const auto measured = options.measured_weber.find(name);
      measured != options.measured_weber.end()) {
    d.weber_fraction = measured->second;
    d.weber_source = "measured (jnd)";
  } else if (const auto typical = typical_weber_fraction(name)) {
    d.weber_fraction = typical->first;
    d.weber_source = typical->second;
  } else {
    d.weber_source = "none";
  }
  if (d.log_scale && d.weber_fraction) {
    const double step = std::log1p(*d.weber_fraction);
    d.spread_steps = d.spread / step;
    d.ci_half_steps = half / step;
  }
  return d;
}

struct Partition {
  std::vector<int> group;
  double within = std::numeric_limits<double>::infinity();
};

// 2-means from every pair of points as starting centres; the lowest within-group sum of squares.
Partition two_means(const std::vector<std::vector<double>>& points) {
  const std::size_t n = points.size(), p = points.front().size();
  const auto distance = [&](const std::vector<double>& a, const std::vector<double>& b) {
    double sum = 0.0;
    for (std::size_t j = 0; j < p; ++j) sum += (a[j] - b[j]) * (a[j] - b[j]);
    return sum;
  };
  Partition best;
  for (std::size_t a = 0; a < n; ++a) {
    for (std::size_t b = a + 1; b < n; ++b) {
      std::vector<std::vector<double>> centres{points[a], points[b]};
      std::vector<int> group(n, -1);
      for (int iteration = 0; iteration < 100; ++iteration) {
        bool changed = false;
        for (std::size_t i = 0; i < n; ++i) {
          const int g = distance(points[i], centres[1]) < distance(points[i], centres[0]) ? 1 : 0;
          changed |= g != group[i];
          group[i] = g;
        }
        if (!changed) break;
        for (int g = 0; g < 2; ++g) {
          std::vector<double> sum(p, 0.0);
          int count = 0;
          for (std::size_t i = 0; i < n; ++i) {
            if (group[i] != g) continue;
            ++count;
            for (std::size_t j = 0; j < p; ++j) sum[j] += points[i][j];
          }
          if (count > 0) {
            for (double& s : sum) s /= count;
            centres[g] = sum;
          }
        }
      }
      double within = 0.0;
      for (std::size_t i = 0; i < n; ++i) within += distance(points[i], centres[group[i]]);
      if (within < best.within - 1e-12) best = {group, within};
    }
  }
  return best;
}

// BIC of k spherical Gaussian groups with a shared variance, given the within sum of squares
// and the group sizes.
double bic(double within, const std::vector<int>& sizes, std::size_t dimensions) {
  double n = 0.0;
  for (const int s : sizes) n += s;
  const double cells = n * static_cast<double>(dimensions);
  const double variance = std::max(within / cells, 1e-300);
  double log_likelihood = -0.5 * cells * (std::log(2.0 * std::numbers::pi * variance) + 1.0);
  for (const int s : sizes) {
    if (s > 0) log_likelihood += s * std::log(s / n);
  }
  const double k = static_cast<double>(sizes.size());
  const double parameters = k * static_cast<double>(dimensions) + 1.0 + (k - 1.0);
  return -2.0 * log_likelihood + parameters * std::log(n);
}

// The distance between the two groups' centres.
double centre_distance(const std::vector<std::vector<double>>& points,
                       const std::vector<int>& group) {
  const std::size_t p = points.front().size();
  std::vector<double> sum[2] = {std::vector<double>(p, 0.0), std::vector<double>(p, 0.0)};
  int count[2] = {0, 0};
  for (std::size_t i = 0; i < points.size(); ++i) {
    ++count[group[i]];
    for (std::size_t j = 0; j < p; ++j) sum[group[i]][j] += points[i][j];
  }
  if (count[0] == 0 || count[1] == 0) return 0.0;
  double squares = 0.0;
  for (std::size_t j = 0; j < p; ++j) {
    const double d = sum[1][j] / count[1] - sum[0][j] / count[0];
    squares += d * d;
  }
  return std::sqrt(squares);
}

TuningClusters cluster(const std::vector<TunedDoor>& doors,
                       const std::vector<ParameterDistribution>& distributions,
                       const TuningOptions& options) {
  TuningClusters out;
  out.group.assign(doors.size(), 0);
  std::vector<std::size_t> columns;
  for (std::size_t j = 0; j < distributions.size(); ++j) {
    if (distributions[j].spread_steps && distributions[j].spread > 0.0) {
      columns.push_back(j);
      out.dimensions.push_back(distributions[j].parameter);
    }
  }
  if (columns.empty() || doors.size() < 4) return out;
  std::vector<std::vector<double>> points;
  for (const TunedDoor& door : doors) {
    std::vector<double> point;
    for (const std::size_t j : columns) {
      point.push_back(std::log(door.parameters[j].second) /
                      std::log1p(*distributions[j].weber_fraction));
    }
    points.push_back(point);
  }
  std::vector<double> mean(columns.size(), 0.0);
  for (const auto& point : points) {
    for (std::size_t j = 0; j < columns.size(); ++j) mean[j] += point[j] / points.size();
  }
  double total = 0.0;
  for (const auto& point : points) {
    for (std::size_t j = 0; j < columns.size(); ++j)
      total += (point[j] - mean[j]) * (point[j] - mean[j]);
  }
  const Partition partition = two_means(points);
  std::vector<int> sizes{0, 0};
  for (const int g : partition.group) ++sizes[g];
  out.bic_one = bic(total, {static_cast<int>(points.size())}, columns.size());
  out.bic_two = bic(partition.within, sizes, columns.size());
  out.separation = centre_distance(points, partition.group);
  out.split = out.bic_two < out.bic_one &&
              std::min(sizes[0], sizes[1]) >= options.min_cluster_size &&
              out.separation >= options.min_separation_steps;
  if (!out.split) return out;
  out.group = partition.group;
  out.centres.resize(2);
  for (int g = 0; g < 2; ++g) {
    for (std::size_t j = 0; j < columns.size(); ++j) {
      double sum = 0.0;
      for (std::size_t i = 0; i < points.size(); ++i) {
        if (out.group[i] == g) sum += std::log(doors[i].parameters[columns[j]].second);
      }
      out.centres[g][out.dimensions[j]] = std::exp(sum / sizes[g]);
    }
  }
  for (std::size_t j = 0; j < columns.size(); ++j) {
    const std::string& name = out.dimensions[j];
    out.separation_steps[name] = std::log(out.centres[1][name] / out.centres[0][name]) /
                                 std::log1p(*distributions[columns[j]].weber_fraction);
  }
  return out;
}

}  // namespace

TuningResult analyze_tuning(std::span<const TunedDoor> doors, const TuningOptions& options) {
  if (const std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument("tuning: " + problem);
  }
  if (doors.empty()) throw std::invalid_argument("tuning: no tuned door");
  TuningResult result;
  result.doors.assign(doors.begin(), doors.end());
  const auto& first = doors.front().parameters;
  for (const TunedDoor& door : doors) {
    bool same = door.parameters.size() == first.size();
    for (std::size_t j = 0; same && j < first.size(); ++j)
      same = door.parameters[j].first == first[j].first;
    if (!same) {
      throw std::invalid_argument("tuning: the door of " + door.participant +
                                  " names other parameters than that of " +
                                  doors.front().participant);
    }
    for (const auto& [name, value] : door.parameters) {
      if (!std::isfinite(value)) {
        throw std::invalid_argument("tuning: the door of " + door.participant + " has " + name +
                                    " not finite");
      }
    }
  }
  for (std::size_t j = 0; j < first.size(); ++j) {
    std::vector<double> values;
    for (const TunedDoor& door : doors) values.push_back(door.parameters[j].second);
    result.parameters.push_back(describe(first[j].first, values, options));
  }
  result.clusters = cluster(result.doors, result.parameters, options);
  return result;
}

nlohmann::json TuningResult::to_json() const {
  nlohmann::json out;
  out["doors"] = nlohmann::json::array();
  for (const TunedDoor& door : doors) {
    nlohmann::json values = nlohmann::json::object();
    for (const auto& [name, value] : door.parameters) values[name] = value;
    out["doors"].push_back(
        {{"participant", door.participant}, {"file", door.file}, {"parameters", values}});
  }
  out["parameters"] = nlohmann::json::array();
  for (const ParameterDistribution& d : parameters) {
    out["parameters"].push_back({{"parameter", d.parameter},
                                 {"scale", d.log_scale ? "log" : "linear"},
                                 {"doors", d.doors},
                                 {"centre", d.centre},
                                 {"spread", d.spread},
                                 {"ci_low", json_number(d.ci_low)},
                                 {"ci_high", json_number(d.ci_high)},
                                 {"min", d.min},
                                 {"max", d.max},
                                 {"weber_fraction", json_number(d.weber_fraction)},
                                 {"weber_source", d.weber_source},
                                 {"spread_steps", json_number(d.spread_steps)},
                                 {"ci_half_steps", json_number(d.ci_half_steps)}});
  }
  nlohmann::json groups = nlohmann::json::array();
  for (std::size_t g = 0; g < clusters.centres.size(); ++g) {
    nlohmann::json members = nlohmann::json::array();
    for (std::size_t i = 0; i < doors.size(); ++i) {
      if (clusters.group[i] == static_cast<int>(g)) members.push_back(doors[i].participant);
    }
    groups.push_back({{"participants", members}, {"centre", clusters.centres[g]}});
  }
  out["clusters"] = {{"split", clusters.split},
                     {"rule",
                      "2-means in perceptual steps; split when BIC(2 groups) < BIC(1), "
                      "each group has enough doors and the centres are far enough apart"},
                     {"separation", clusters.separation},
                     {"bic_one", clusters.bic_one},
                     {"bic_two", clusters.bic_two},
                     {"dimensions", clusters.dimensions},
                     {"groups", groups},
                     {"separation_steps", clusters.separation_steps}};
  return out;
}

std::vector<TunedDoor> tuned_doors(const TrialsTable& table, const std::filesystem::path& folder) {
  std::vector<TunedDoor> doors;
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    if (!is_question(table.value(r, "question"), QuestionKind::kTune)) continue;
    const std::string& file = table.value(r, "answer");
    if (file.empty()) {
      throw TrialsTableError(table.source, table.line_numbers[r],
                             "answer is empty (a tune row names its tuned parameter file)");
    }
    const std::filesystem::path path = folder / file;
    const ParameterFile parsed = parse_parameter_file(read_text_file(path), path.string());
    TunedDoor door{table.value(r, "participant"), file, {}};
    if (parsed.sensory) {
      for (std::size_t j = 0; j < parsed.sensory->values.size(); ++j) {
        door.parameters.emplace_back(std::string(sensory::kParameterInfo[j].name),
                                     parsed.sensory->values[j]);
      }
    }
    if (parsed.physical) {
      for (std::size_t j = 0; j < parsed.physical->values.size(); ++j) {
        std::string name(physical::kParameterInfo[j].name);
        const bool taken = std::any_of(door.parameters.begin(), door.parameters.end(),
                                       [&](const auto& p) { return p.first == name; });
        door.parameters.emplace_back(taken ? "physical." + name : name, parsed.physical->values[j]);
      }
    }
    const auto same = std::find_if(doors.begin(), doors.end(), [&](const TunedDoor& d) {
      return d.participant == door.participant;
    });
    if (same != doors.end()) {
      *same = std::move(door);  // the last tuning counts
    } else {
      doors.push_back(std::move(door));
    }
  }
  return doors;
}

namespace {

struct TuningPlotData {
  PlotOptions options;
  std::vector<std::vector<double>> x, y;
  std::vector<PlotSeries> series;
};

TuningPlotData tuning_plot_data(const TuningResult& tuning) {
  TuningPlotData data;
  std::vector<std::size_t> columns;
  std::string names;
  for (std::size_t j = 0; j < tuning.parameters.size(); ++j) {
    if (!tuning.parameters[j].spread_steps) continue;
    columns.push_back(j);
    names += (names.empty() ? "" : ", ") + std::to_string(columns.size()) + " = " +
             tuning.parameters[j].parameter;
  }
  if (columns.empty())
    throw std::invalid_argument("tuning plot: no parameter has perceptual steps");
  data.options.title = "Tuned doors, perceptual steps from the panel's centre";
  data.options.x_label = "parameter (" + names + ")";
  data.options.y_label = "steps from the panel's geometric mean [JND]";
  for (const TunedDoor& door : tuning.doors) {
    std::vector<double> x, y;
    for (std::size_t c = 0; c < columns.size(); ++c) {
      const ParameterDistribution& d = tuning.parameters[columns[c]];
      x.push_back(static_cast<double>(c + 1));
      y.push_back(std::log(door.parameters[columns[c]].second / d.centre) /
                  std::log1p(*d.weber_fraction));
    }
    data.x.push_back(std::move(x));
    data.y.push_back(std::move(y));
  }
  static const char* kGroupColours[] = {"#1f77b4", "#d62728"};
  for (std::size_t i = 0; i < tuning.doors.size(); ++i) {
    const int group = tuning.clusters.split ? tuning.clusters.group[i] : 0;
    data.series.push_back(
        {tuning.doors[i].participant + (tuning.clusters.split ? group == 0 ? " (A)" : " (B)" : ""),
         data.x[i], data.y[i], kGroupColours[group], plot_style::Meaning::kTuned});
  }
  return data;
}

}  // namespace

std::string render_tuning_plot(const TuningResult& tuning) {
  const TuningPlotData data = tuning_plot_data(tuning);
  return render_svg_plot(data.options, data.series);
}

void write_tuning_plot(const std::string& path, const TuningResult& tuning) {
  const TuningPlotData data = tuning_plot_data(tuning);
  write_svg_plot(path, data.options, data.series);
}

}  // namespace doorbench::study
