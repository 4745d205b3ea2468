#include "analysis/design/tolerance_analysis.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <mutex>
#include <nlohmann/json.hpp>
#include <random>
#include <stdexcept>
#include <thread>

#include "core/number_format.h"
#include "core/numbers.h"
#include "core/percentile.h"
#include "core/seeded_random.h"
#include "core/units.h"

namespace doorbench {

namespace {

struct DefaultTolerance {
  std::string_view name;
  double plus_minus;
  bool percent;
};

// Typical sheet-metal, spring and moulding tolerances (docs/design-spec.md says why each).
// Smoothing lengths and the end stops are modelling devices, not made parts: no tolerance.
constexpr DefaultTolerance kPhysicalDefaults[] = {
    {"m_d", 2.0, true},
    {"l_c", 0.002, false},
    {"J_d", 3.0, true},
    {"k_s", 5.0, true},
    {"L0", 0.0005, false},
    {"F0", 5.0, true},
    {"A_x", 0.0003, false},
    {"A_y", 0.0003, false},
    {"B_u", 0.0003, false},
    {"B_v", 0.0003, false},
    {"T_h", 20.0, true},
    {"b_h", 20.0, true},
    {"mu_g", 20.0, true},
    {"r_l", 0.0005, false},
    {"k_l", 10.0, true},
    {"F_l0", 10.0, true},
    {"h", 0.0001, false},
    {"alpha_o", kRadPerDeg, false},
    {"alpha_c", kRadPerDeg, false},
    {"mu_l", 20.0, true},
    {"k_seal", 15.0, true},
    {"theta_seal", 0.002, false},
};

}  // namespace

std::string_view to_string(ToleranceDistribution distribution) {
  return distribution == ToleranceDistribution::kUniform ? "uniform" : "normal";
}

double ParameterTolerance::absolute(double nominal) const {
  return percent ? std::abs(nominal) * plus_minus / 100.0 : plus_minus;
}

const ParameterTolerance* ToleranceSpec::find(std::string_view name) const {
  for (const ParameterTolerance& t : parameters) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

ToleranceSpec default_tolerances(const DoorModel& model) {
  ToleranceSpec spec;
  if (model.kind() != ModelKind::kPhysical) return spec;
  for (const DefaultTolerance& d : kPhysicalDefaults) {
    if (!model.find_parameter(d.name)) continue;
    spec.parameters.push_back(
        {std::string(d.name), d.plus_minus, d.percent, ToleranceDistribution::kNormal});
  }
  return spec;
}

ToleranceSpec parse_tolerance_file(std::string_view json_text, std::string_view source,
                                   const DoorModel& model) {
  using json = nlohmann::ordered_json;
  const std::string where(source);
  json root;
  try {
    root = json::parse(json_text);
  } catch (const json::exception& error) {  // also numbers beyond a double
    throw std::runtime_error(where + ": " + error.what());
  }
  if (!root.is_object()) throw std::runtime_error(where + ": a JSON object of parameters expected");
  ToleranceSpec spec = default_tolerances(model);
  if (root.contains("use_defaults")) {
    if (!root["use_defaults"].is_boolean()) {
      throw std::runtime_error(where + ": use_defaults must be true or false");
    }
    if (!root["use_defaults"].get<bool>()) spec.parameters.clear();
  }
  for (const auto& [name, entry] : root.items()) {
    if (name == "use_defaults") continue;
    const std::string key = where + ": " + name;
    if (!model.find_parameter(name)) throw std::runtime_error(key + ": no such parameter");
    if (!entry.is_object()) throw std::runtime_error(key + ": an object with plus_minus expected");
    ParameterTolerance tolerance;
    tolerance.name = name;
    bool has_plus_minus = false;
    for (const auto& [field, value] : entry.items()) {
      if (field == "plus_minus") {
        has_plus_minus = true;
        if (value.is_number()) {
          tolerance.plus_minus = value.get<double>();
        } else if (value.is_string()) {
          std::string text = value.get<std::string>();
          if (text.empty() || text.back() != '%') {
            throw std::runtime_error(key + ".plus_minus: a number or a string like \"5%\"");
          }
          text.pop_back();
          std::size_t used = 0;
          try {
            tolerance.plus_minus = std::stod(text, &used);
          } catch (const std::exception&) {
            used = 0;
          }
          if (used == 0 || used != text.size()) {
            throw std::runtime_error(key + ".plus_minus: a number or a string like \"5%\"");
          }
          tolerance.percent = true;
        } else {
          throw std::runtime_error(key + ".plus_minus: a number or a string like \"5%\"");
        }
        if (!(tolerance.plus_minus >= 0) || !std::isfinite(tolerance.plus_minus)) {
          throw std::runtime_error(key + ".plus_minus must be >= 0");
        }
      } else if (field == "distribution") {
        const std::string d = value.is_string() ? value.get<std::string>() : "";
        if (d == "normal") {
          tolerance.distribution = ToleranceDistribution::kNormal;
        } else if (d == "uniform") {
          tolerance.distribution = ToleranceDistribution::kUniform;
        } else {
          throw std::runtime_error(key + ".distribution must be \"normal\" or \"uniform\"");
        }
      } else {
        throw std::runtime_error(key + ": unknown key " + field);
      }
    }
    if (!has_plus_minus) throw std::runtime_error(key + ": plus_minus missing");
    // (A named copy: clang 14, which builds the fuzz targets, cannot capture a binding.)
    const std::string parameter = name;
    std::erase_if(spec.parameters,
                  [&parameter](const ParameterTolerance& t) { return t.name == parameter; });
    if (tolerance.plus_minus > 0) spec.parameters.push_back(tolerance);
  }
  return spec;
}

std::string MonteCarloOptions::validate() const {
  if (samples < 2) return "monte carlo samples must be >= 2";
  if (first_sample < 0) return "monte carlo first_sample must be >= 0";
  if (threads < 0) return "monte carlo threads must be >= 0";
  return felt.validate();
}

namespace {

// The toleranced parameters' model indices; result.tolerances and nominal_values filled.
std::vector<int> toleranced_parameters(const DoorModel& design, const ToleranceSpec& spec,
                                       ToleranceResult& result) {
  std::vector<int> index;
  for (const ParameterTolerance& t : spec.parameters) {
    const std::optional<int> i = design.find_parameter(t.name);
    if (!i) throw std::invalid_argument("tolerance for " + t.name + ": no such parameter");
    if (!(t.plus_minus >= 0) || !std::isfinite(t.plus_minus)) {
      throw std::invalid_argument("tolerance for " + t.name + ": plus_minus must be >= 0");
    }
    index.push_back(*i);
    result.tolerances.push_back(t);
    result.nominal_values.push_back(design.parameter_values()[*i]);
  }
  return index;
}

// Sample s: its own generator seeded from (seed, first_sample + s), every toleranced parameter
// drawn within its band (clamped to its bounds), the felt quantities of that door; `failure` set
// when the model refuses the draw or the run fails.
void run_sample(const DoorModel& design, const std::vector<int>& index,
                const MonteCarloOptions& options, std::size_t s, ToleranceResult& result,
                std::string& failure) {
  const auto drawn = static_cast<std::uint64_t>(options.first_sample) + s;
  std::mt19937_64 random(mix64(options.seed * 0x100000001b3ULL + drawn));
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  std::vector<double> values(design.parameter_values().begin(), design.parameter_values().end());
  for (std::size_t p = 0; p < index.size(); ++p) {
    const ParameterTolerance& t = result.tolerances[p];
    const double nominal = result.nominal_values[p];
    const double band = t.absolute(nominal);
    double unit;
    if (t.distribution == ToleranceDistribution::kUniform) {
      unit = uniform(random);
    } else {
      do {
        unit = normal(random) / 3.0;
      } while (std::abs(unit) > 1.0);
    }
    const Bounds bounds = design.parameter_bounds()[index[p]];
    const double value = std::clamp(nominal + band * unit, bounds.lower, bounds.upper);
    values[index[p]] = value;
    result.draws[s][p] = value;
  }
  try {
    result.felt[s] = felt_quantities(design.with_parameter_values(values), options.felt);
  } catch (const std::exception& error) {
    failure = error.what();
  }
}

// Runs `sample(s)` for every s on a pool of threads (options.threads; 0: every core),
// reporting progress serialized. Returns the number of threads used; throws StopRequested
// when options.stop_requested ended the samples early.
int run_pool(const MonteCarloOptions& options, const std::function<void(std::size_t)>& sample) {
  const auto samples = static_cast<std::size_t>(options.samples);
  unsigned threads = options.threads > 0 ? static_cast<unsigned>(options.threads)
                                         : std::max(1u, std::thread::hardware_concurrency());
  threads = std::min<unsigned>(threads, static_cast<unsigned>(samples));
  std::atomic<std::size_t> next{0};
  std::atomic<int> done{0};
  std::mutex progress_mutex;
  int reported = 0;  // the largest count reported (under the mutex): reports only grow
  const int report_every = std::max(1, options.samples / 20);
  if (options.progress) options.progress(0, options.samples);
  std::atomic<bool> stopped{false};
  auto worker = [&] {
    for (std::size_t s = next++; s < samples; s = next++) {
      if (stopped.load(std::memory_order_relaxed) || stop_requested(options.stop_requested)) {
        stopped.store(true, std::memory_order_relaxed);
        return;
      }
      sample(s);
      const int finished = ++done;
      if (options.progress && (finished % report_every == 0 || finished == options.samples)) {
        const std::lock_guard lock(progress_mutex);
        // Another thread may have reported a larger count since this one's increment.
        if (finished > reported) {
          reported = finished;
          options.progress(finished, options.samples);
        }
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& thread : pool) thread.join();
  if (stopped.load()) throw StopRequested("the tolerance Monte Carlo");
  return static_cast<int>(threads);
}

// Quantity q's spread over the samples where it is defined, and each parameter's share of
// its variance (the squared correlation of its draws with the quantity) into explained[q].
QuantitySpread quantity_spread(std::size_t q, ToleranceResult& result) {
  const auto member = kFeltQuantities[q].member;
  QuantitySpread spread;
  spread.name = std::string(kFeltQuantities[q].name);
  spread.nominal = result.nominal.*member;
  std::vector<double> values;
  std::vector<std::size_t> used;
  for (std::size_t s = 0; s < result.felt.size(); ++s) {
    const double v = result.felt[s].*member;
    if (!std::isfinite(v)) continue;
    values.push_back(v);
    used.push_back(s);
  }
  spread.count = static_cast<int>(values.size());
  const double n = static_cast<double>(values.size());
  if (values.size() < 2) {
    spread.mean = spread.sd = spread.p5 = spread.p95 = spread.min = spread.max = kNaN;
    return spread;
  }
  double sum = 0;
  for (double v : values) sum += v;
  spread.mean = sum / n;
  double square = 0;
  for (double v : values) square += (v - spread.mean) * (v - spread.mean);
  spread.sd = std::sqrt(square / (n - 1));
  std::vector<double> sorted = values;
  std::sort(sorted.begin(), sorted.end());
  spread.p5 = percentile_of_sorted(sorted, 0.05);
  spread.p95 = percentile_of_sorted(sorted, 0.95);
  spread.min = sorted.front();
  spread.max = sorted.back();
  for (std::size_t p = 0; p < result.tolerances.size(); ++p) {
    double mean_x = 0;
    for (std::size_t s : used) mean_x += result.draws[s][p];
    mean_x /= n;
    double sxy = 0, sxx = 0, syy = 0;
    for (std::size_t k = 0; k < used.size(); ++k) {
      const double dx = result.draws[used[k]][p] - mean_x;
      const double dy = values[k] - spread.mean;
      sxy += dx * dy;
      sxx += dx * dx;
      syy += dy * dy;
    }
    result.explained[q][p] = sxx > 0 && syy > 0 ? sxy * sxy / (sxx * syy) : 0.0;
  }
  return spread;
}

// The parameter explaining most of quantity q's variance ("" when none explains any).
std::string most_important(std::size_t q, const ToleranceResult& result) {
  std::string most;
  double best = 0.0;
  for (std::size_t p = 0; p < result.tolerances.size(); ++p) {
    if (result.explained[q][p] > best) {
      best = result.explained[q][p];
      most = result.tolerances[p].name;
    }
  }
  return most;
}

}  // namespace

ToleranceResult tolerance_analysis(const DoorModel& design, const ToleranceSpec& spec,
                                   const MonteCarloOptions& options) {
  if (std::string error = options.validate(); !error.empty()) throw std::invalid_argument(error);
  const auto start = std::chrono::steady_clock::now();
  ToleranceResult result;
  result.samples = options.samples;
  const std::vector<int> index = toleranced_parameters(design, spec, result);
  result.nominal = felt_quantities(design, options.felt);

  const auto samples = static_cast<std::size_t>(options.samples);
  result.draws.assign(samples, std::vector<double>(index.size(), kNaN));
  const FeltQuantities failed{kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN, kNaN};
  result.felt.assign(samples, failed);
  std::vector<std::string> failure(samples);
  result.threads = run_pool(
      options, [&](std::size_t s) { run_sample(design, index, options, s, result, failure[s]); });
  for (std::size_t s = 0; s < samples; ++s) {
    if (failure[s].empty()) continue;
    if (result.failed++ == 0) {
      result.first_failure = printf_text("sample %zu: %s", s, failure[s].c_str());
    }
  }

  result.explained.assign(kFeltQuantities.size(), std::vector<double>(index.size(), 0.0));
  for (std::size_t q = 0; q < kFeltQuantities.size(); ++q) {
    result.spreads.push_back(quantity_spread(q, result));
    result.most_important.push_back(most_important(q, result));
  }
  result.elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

std::string ToleranceResult::brief_report() const {
  std::string text =
      printf_text("  %d samples (%d failed) of %zu toleranced parameters, %d threads, %.1f s\n",
                  samples, failed, tolerances.size(), threads, elapsed_s);
  text +=
      "  quantity (standard run)              nominal     mean       sd       p5      p95  most "
      "important\n";
  for (std::size_t q = 0; q < spreads.size(); ++q) {
    const QuantitySpread& s = spreads[q];
    double share = 0.0;
    for (std::size_t p = 0; p < tolerances.size(); ++p) {
      if (tolerances[p].name == most_important[q]) share = explained[q][p];
    }
    const std::string label = q < kFeltQuantities.size() ? felt_label(kFeltQuantities[q]) : s.name;
    text += printf_text("  %-34s %8.2f %8.2f %8.2f %8.2f %8.2f  %s (%.0f %%)\n", label.c_str(),
                        s.nominal, s.mean, s.sd, s.p5, s.p95,
                        most_important[q].empty() ? "-" : most_important[q].c_str(), 100.0 * share);
  }
  if (failed > 0) text += "  first failure: " + first_failure + "\n";
  return text;
}

}  // namespace doorbench
