// The global stage's sample and its distinct optima (internal/fit_search.h).
#include "analysis/fit/internal/fit_search.h"

#include <algorithm>
#include <boost/random/mersenne_twister.hpp>
#include <boost/random/normal_distribution.hpp>
#include <boost/random/sobol.hpp>
#include <cmath>
#include <stdexcept>

#include "analysis/fit/search_scale.h"

namespace doorbench::fit_detail {

namespace {

// Bounds spanning more than this ratio from a lower bound >= 0 are sampled on a log scale, from
// the upper bound times kLogFloor at least.
constexpr double kLogSpan = 100.0;
constexpr double kLogFloor = 1e-3;

// Sobol sequences draw at most this many sequence points per point asked for; a hop tries at
// most this many steps.
constexpr int kTriesPerPoint = 20;

// The sample's scale of one parameter: u in [0, 1] across its bounds, linear, or logarithmic
// where the bounds span more than kLogSpan from a lower bound >= 0.
struct UnitScale {
  bool logarithmic = false;
  double lower = 0.0, upper = 1.0;

  explicit UnitScale(const Bounds& b) : lower(b.lower), upper(b.upper) {
    const double log_lower = std::max(b.lower, b.upper * kLogFloor);
    logarithmic = b.lower >= 0 && b.upper > kLogSpan * b.lower && log_lower > 0;
    if (logarithmic) lower = log_lower;
  }
  double value(double u) const {
    return logarithmic ? lower * std::pow(upper / lower, u) : lower + u * (upper - lower);
  }
  double unit(double value) const {
    const double u = logarithmic
                         ? std::log(std::max(value, lower) / lower) / std::log(upper / lower)
                         : (value - lower) / (upper - lower);
    return std::clamp(u, 0.0, 1.0);
  }
};

}  // namespace

std::vector<std::vector<double>> space_filling_sample(const DoorModel& model,
                                                      const ParameterMap& map, int count,
                                                      int seed) {
  const int p = map.free_count();
  std::vector<std::vector<double>> points;
  if (count <= 0 || p == 0) return points;
  boost::random::sobol sequence(static_cast<std::size_t>(p));
  sequence.seed(static_cast<boost::uint_least64_t>(seed));
  const auto bounds = model.parameter_bounds();
  const std::span<const double> model_values = model.parameter_values();
  for (int tried = 0; static_cast<int>(points.size()) < count && tried < kTriesPerPoint * count;
       ++tried) {
    std::vector<double> values(model_values.begin(), model_values.end());
    for (int k = 0; k < p; ++k) {
      // The generator's integers span [0, 2^64): u in [0, 1).
      const double u = std::ldexp(static_cast<double>(sequence()), -64);
      values[static_cast<std::size_t>(map.free_index[k])] =
          UnitScale(bounds[static_cast<std::size_t>(map.free_index[k])]).value(u);
    }
    try {
      (void)model.with_parameter_values(values);
      points.push_back(std::move(values));
    } catch (const std::invalid_argument&) {
      // A point that breaks a constraint (θ0 < θ1 < ... ): the next one.
    }
  }
  return points;
}

std::vector<double> hop_point(const DoorModel& model, const ParameterMap& map, double size,
                              std::uint32_t seed) {
  boost::random::mt19937 generator(seed);
  boost::random::normal_distribution<double> step(0.0, size);
  const auto bounds = model.parameter_bounds();
  const std::span<const double> model_values = model.parameter_values();
  for (int tried = 0; tried < kTriesPerPoint; ++tried) {
    std::vector<double> values(model_values.begin(), model_values.end());
    for (int k = 0; k < map.free_count(); ++k) {
      const std::size_t i = static_cast<std::size_t>(map.free_index[k]);
      const UnitScale scale(bounds[i]);
      values[i] = scale.value(std::clamp(scale.unit(values[i]) + step(generator), 0.0, 1.0));
    }
    try {
      (void)model.with_parameter_values(values);
      return values;
    } catch (const std::invalid_argument&) {
      // A step that breaks a constraint (θ0 < θ1 < ... ): another step.
    }
  }
  return {};
}

std::vector<double> free_values(const ParameterMap& map, const std::vector<double>& x) {
  const std::vector<double> values = map.values(x.data());
  std::vector<double> free;
  for (int k = 0; k < map.free_count(); ++k) {
    free.push_back(values[static_cast<std::size_t>(map.free_index[k])]);
  }
  return free;
}

void distinct_optima(const std::vector<PolishedOptimum>& polished, std::size_t fit,
                     GlobalSearch& global) {
  std::vector<std::size_t> order(polished.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if ((a == fit) != (b == fit)) return a == fit;
    return polished[a].cost < polished[b].cost;
  });
  global.optima.clear();
  for (std::size_t i : order) {
    const PolishedOptimum& optimum = polished[i];
    const std::vector<double>& free_values = optimum.free_values;
    GlobalOptimum* same = nullptr;
    for (GlobalOptimum& known : global.optima) {
      bool alike = std::abs(optimum.cost - known.cost) <=
                   GlobalSearch::kSameOptimumCost * std::max(std::abs(known.cost), 1e-300);
      for (std::size_t k = 0; alike && k < free_values.size(); ++k) {
        const double a = free_values[k];
        const double b = known.free_values[k];
        alike = std::abs(a - b) <=
                GlobalSearch::kSameOptimumParameter * std::max({std::abs(a), std::abs(b), 1e-300});
      }
      if (alike) {
        same = &known;
        break;
      }
    }
    if (same != nullptr) {
      same->reached_from.push_back(optimum.origin);
      continue;
    }
    global.optima.push_back({optimum.cost, optimum.fit_percent, {optimum.origin}, free_values});
  }
  global.reached_best =
      global.optima.empty() ? 0 : static_cast<int>(global.optima.front().reached_from.size());
  global.best_from = global.optima.empty() ? "" : global.optima.front().reached_from.front();
}

}  // namespace doorbench::fit_detail

namespace doorbench {

bool search_scale_is_logarithmic(const Bounds& bounds) {
  return fit_detail::UnitScale(bounds).logarithmic;
}

double search_scale_place(const Bounds& bounds, double value) {
  return fit_detail::UnitScale(bounds).unit(value);
}

}  // namespace doorbench
