#pragma once
// The data and start of the sensory fit benchmark (bench_fitting.cpp), shared with
// export_fit_strokes.cpp so that the SciPy and genetic-algorithm comparisons in
// studies/compare/ fit exactly the strokes and start that the C++ benchmark times.
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/model/parameter_file.h"
#include "analysis/model/sensory_model.h"
#include "analysis/simulation/fit_synthetic.h"

namespace doorbench::bench {

// Six openings to 29°–80° and their closings (the virtual hand's opening and closing each
// take 0.35 of the run: 2.6 to 3.3 s), the bench's noise, seed 7.
inline SyntheticStrokeOptions fit_benchmark_stroke_options() {
  SyntheticStrokeOptions options;
  options.runs = {{0.5, 7.5}, {0.7, 8.0}, {0.9, 8.5}, {1.1, 9.0}, {1.25, 8.5}, {1.4, 9.5}};
  options.seed = 7;
  return options;
}

inline PreparedData fit_benchmark_strokes() {
  return synthetic_strokes(reference_model(ModelKind::kSensory), fit_benchmark_stroke_options());
}

// 30% off on J … θ4: alternately ×0.7 and ×1.3, and the latch angles θ0…θ3 all ×1.3 (so
// that their order holds).
inline DoorModel fit_benchmark_start() {
  const DoorModel truth = reference_model(ModelKind::kSensory);
  std::vector<double> values(truth.parameter_values().begin(), truth.parameter_values().end());
  for (int i = 0; i <= sensory::kTheta4; ++i) values[i] *= i % 2 == 1 ? 1.3 : 0.7;
  for (int i = sensory::kTheta0; i <= sensory::kTheta3; ++i) {
    values[i] = truth.parameter_values()[i] * 1.3;
  }
  return truth.with_parameter_values(values);
}

}  // namespace doorbench::bench
