// A 10 s opening-closing by the virtual hand at 1 kHz output, every term recorded
// (target: at least 1000x real time for the sensory model). The counter
// "realtime_factor" is simulated seconds per wall-clock second.
#include <benchmark/benchmark.h>

#include "analysis/model/parameter_file.h"
#include "analysis/simulation/virtual_hand.h"

namespace {

using namespace doorbench;

void open_close_10s(benchmark::State& state, ModelKind kind) {
  const DoorModel model = reference_model(kind);
  const VirtualHand hand(VirtualHandOptions{}, model.geometry().handle_radius_m);
  std::vector<double> times(10001);
  for (std::size_t i = 0; i < times.size(); ++i) times[i] = static_cast<double>(i) * 1e-3;
  long steps = 0;
  for (auto _ : state) {
    Trajectory run = simulate(model, hand, DoorState{}, times);
    steps = run.stats.accepted_steps;
    benchmark::DoNotOptimize(run.theta_rad.data());
  }
  state.counters["realtime_factor"] = benchmark::Counter(
      10.0 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["steps"] = static_cast<double>(steps);
}

BENCHMARK_CAPTURE(open_close_10s, sensory, ModelKind::kSensory)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(open_close_10s, physical, ModelKind::kPhysical)->Unit(benchmark::kMillisecond);

}  // namespace
