// Fitting the sensory model to 12 strokes of about 3 s at 1 kHz (six openings to 29°-80°
// and the six closings, the bench's noise), from a start 30% off (target: under 1 s), and
// the same with held-out metrics by 4-fold cross-validation. Everything fit_model does is
// timed: the latch read-off, the equation-error stage, the window fit, the statistics and
// the metrics (whole strokes replayed).
#include <benchmark/benchmark.h>

#include "analysis/fit/fitting.h"
#include "bench/fit_benchmark_data.h"

namespace {

using namespace doorbench;

const PreparedData& twelve_strokes() {
  static const PreparedData data = bench::fit_benchmark_strokes();
  return data;
}

DoorModel thirty_percent_off() {
  return bench::fit_benchmark_start();
}

void fit_sensory_12_strokes(benchmark::State& state) {
  const PreparedData& data = twelve_strokes();
  const DoorModel start = thirty_percent_off();
  FitOptions options;
  options.cross_validation_folds = static_cast<int>(state.range(0));
  std::size_t samples = 0;
  for (const Stroke& stroke : data.strokes) samples += stroke.size();
  int iterations = 0;
  for (auto _ : state) {
    FitResult result = fit_model(start, data, options);
    iterations = result.summary.iterations;
    benchmark::DoNotOptimize(result.model.parameter_values().data());
  }
  state.counters["strokes"] = static_cast<double>(data.strokes.size());
  state.counters["samples"] = static_cast<double>(samples);
  state.counters["window_iterations"] = iterations;
}

BENCHMARK(fit_sensory_12_strokes)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(fit_sensory_12_strokes)->Arg(4)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
