#pragma once
// A residual loop's result.json: written by loop_result_json from the LoopResult and the data
// it ran on (the steps with their evidence, parameters and errors before and after, the
// candidates, the structure check, and the start and final fits as fit_result_json writes
// them), and read back by read_loop_result (the viewer's loop layout, `view --loop`). The
// writer and the reader of the format are here together, beside the LoopResult.
//
// Errors: read_loop_result throws std::runtime_error naming the file and the missing or
// wrong field ("FILE: steps[2].before: no field 'fitted_rmse_rad_s'").
// Thread safety: pure functions of their arguments and the file read.
#include <filesystem>
#include <string>
#include <vector>

#include "analysis/loop/residual_loop.h"

namespace doorbench {

// result.json's text (two-space indent, a final newline). A number that is not finite is null.
std::string loop_result_json(const LoopResult& result, const PreparedData& data);

// One step read back: the effect, its parameters, the window RMSE of ω on fitted and
// held-out strokes before and after it (NaN where the file has null).
struct LoopResultStep {
  struct Parameter {
    std::string name = "?", unit;
    double value = 0.0;
    double standard_uncertainty = 0.0;  // NaN when not estimated
  };
  int number = 0;
  std::string effect;
  std::vector<Parameter> parameters;
  double fitted_before_rad_s = 0.0, fitted_after_rad_s = 0.0;
  double held_out_before_rad_s = 0.0, held_out_after_rad_s = 0.0;
  double held_out_improvement = 0.0;
  double bic_change = 0.0;
};

struct LoopResultFile {
  std::filesystem::path path;  // the result.json read
  std::string source;          // the data the loop ran on ("" when the file does not say)
  std::vector<LoopResultStep> steps;
};

// Reads DIR/result.json (or the file itself).
LoopResultFile read_loop_result(const std::filesystem::path& dir_or_file);

}  // namespace doorbench
