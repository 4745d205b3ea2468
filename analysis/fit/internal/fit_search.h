#pragma once
// The global stage's sample and its account of the optima (analysis/fit/ only; fit_search.cpp,
// used by fitting.cpp; docs/fitting.md, "The global stage"). Pure functions of their
// arguments, safe on any thread.
#include <cstdint>
#include <string>
#include <vector>

#include "analysis/fit/fit_windows.h"
#include "analysis/fit/fitting.h"
#include "analysis/model/door_model.h"

namespace doorbench::fit_detail {

// `count` points of the Sobol sequence over the free parameters of `map` (from point `seed`
// on: the same seed, the same points), each free parameter spread over its bounds, linearly or
// logarithmically where its bounds span more than two decades from a lower bound >= 0 (then
// over [max(lower, upper / 1000), upper]); the other parameters keep `model`'s values. Points
// that break one of the model's constraints are skipped, at most 20 sequence points tried per
// point asked for. Each point is every parameter's value, in the model's order.
std::vector<std::vector<double>> space_filling_sample(const DoorModel& model,
                                                      const ParameterMap& map, int count, int seed);

// A basin hop from `model` (FitOptions::global_hops): each free parameter moved by a normal
// step of standard deviation `size` on the sample's scale of its bounds (u in [0, 1], linear
// or logarithmic as space_filling_sample spreads it; clamped to the bounds), the generator
// seeded with `seed`. A step that breaks a constraint is drawn again, at most 20 times; empty
// when none held. Every parameter's value, in the model's order.
std::vector<double> hop_point(const DoorModel& model, const ParameterMap& map, double size,
                              std::uint32_t seed);

// An optimum the global stage polished: where it started, its window cost and FIT%, and its
// free parameters' values in their units (each polish scales its parameters by its own start,
// so scaled values of two polishes do not compare).
struct PolishedOptimum {
  std::string origin;
  double cost = 0.0;
  double fit_percent = 0.0;
  std::vector<double> free_values;
};

// The free parameters' values (in their units, the map's free order) at the scaled values x.
std::vector<double> free_values(const ParameterMap& map, const std::vector<double>& x);

// Fills global.optima (the distinct optima by GlobalSearch's rule: the fit's first, the fit
// being polished[fit], then the others by cost), global.reached_best and global.best_from
// from the polishes, the first start's first.
void distinct_optima(const std::vector<PolishedOptimum>& polished, std::size_t fit,
                     GlobalSearch& global);

}  // namespace doorbench::fit_detail
