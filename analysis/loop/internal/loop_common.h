#pragma once
// What the residual loop's parts share (analysis/loop/ only: the examination in
// residual_examination.cpp, the loop and its refits in residual_loop.cpp, the reports in
// loop_report.cpp): the loop's numbers as text and the threads of its refits.
// Pure functions, safe on any thread.
#include <cstddef>
#include <string>

#include "analysis/fit/fitting.h"
#include "analysis/loop/residual_loop.h"

namespace doorbench::loop_detail {

// The threads for `count` refits: one each when they run at once (each refit is a fit of
// its own, so they balance as whole tasks), else the caller's alone.
inline int refit_threads(bool parallel, std::size_t count) {
  return parallel ? static_cast<int>(count) : 1;
}

// Four significant digits: the loop's tables and its reasons.
std::string number(double value);

// "window RMSE of omega A rad/s fitted, B held out".
std::string describe_figures(const ModelFigures& figures);

// One fitted parameter as a report line: "name = value +- uncertainty unit" and its flags
// ((fixed), [at a bound], [undetermined]).
std::string parameter_text(const FittedParameter& parameter);

}  // namespace doorbench::loop_detail
