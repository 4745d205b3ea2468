#pragma once
// The set-up of a fit (analysis/fit/ only; fit_setup.cpp, used by fitting.cpp): the data
// checked, the weights resolved, the free parameters and their start values (the latch
// read off the data when asked, clamped into bounds), the solver's parameter map with the
// priors. Errors are std::invalid_argument with a message starting "fit: ". Pure functions
// of their arguments, safe on any thread.
#include <string>
#include <vector>

#include "analysis/fit/fit_problem.h"
#include "analysis/fit/fitting.h"

namespace doorbench::fit_detail {

// Throws when the data has no strokes, a stroke's columns differ in length, hold a value
// that is not finite or times that do not increase, or the data's handle radius differs
// from the model's.
void check_data(const PreparedData& data, const DoorModel& model);

// The residuals' weights: the noise levels given, else the data's, else the bench's (noted).
FitWeights resolve_weights(const FitOptions& options, const PreparedData& data,
                           std::vector<std::string>& notes);

// The start: free parameters, the start values (the latch read off the data when asked,
// clamped into bounds) and where each value came from.
struct StartValues {
  std::vector<int> free_index;
  std::vector<double> values;
  std::vector<std::string> origin;
};

StartValues start_values(const DoorModel& start, const PreparedData& data,
                         const FitOptions& options, const FitWeights& weights, FitSummary& summary);

// The start model with `values`; throws "fit: the start breaks a constraint: ..." when it
// breaks one.
DoorModel checked_start_model(const DoorModel& start, const std::vector<double>& values);

// The solver's map of the free parameters, and the priors on them in its units.
ParameterMap make_map(const DoorModel& start, const StartValues& chosen, const FitOptions& options,
                      FitWeights& weights, FitSummary& summary);

}  // namespace doorbench::fit_detail
