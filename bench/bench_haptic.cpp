// The render loop's tick: its cost alone (a device that costs nothing, records drained outside
// the timing every 50000 ticks), for the sensory and the physical reference door.
#include <benchmark/benchmark.h>

#include "analysis/parameter_file.h"
#include "bench/haptic_fixed_device.h"
#include "haptic/render_loop.h"

namespace {

using namespace doorbench;

void tick_cost(benchmark::State& state, ModelKind kind) {
  const DoorModel model = reference_model(kind);
  const haptic::DoorMapping mapping(haptic::Kinematics::kCartesian3, haptic::ArcGeometry{},
                                    model.geometry().handle_radius_m);
  bench::FixedPathDevice device(mapping);
  haptic::RenderLoopOptions options;
  options.safety.max_tick_interval_s = 1e9;  // the benchmark's clock is not the ticks'
  haptic::RenderLoop loop(device, mapping,
                          std::make_unique<haptic::PlaybackParameters>(model, mapping, "bench"),
                          options);
  double time_s = 0.0;
  long ticks = 0;
  for (auto _ : state) {
    loop.tick(time_s);
    time_s += 1e-3;
    if (++ticks % 50000 == 0) {
      state.PauseTiming();
      while (loop.records().consumer_slot()) loop.records().release();
      state.ResumeTiming();
    }
  }
  benchmark::DoNotOptimize(device.last_command());
  state.counters["ticks"] = static_cast<double>(ticks);
}

void BM_RenderLoopTickSensory(benchmark::State& state) {
  tick_cost(state, ModelKind::kSensory);
}
void BM_RenderLoopTickPhysical(benchmark::State& state) {
  tick_cost(state, ModelKind::kPhysical);
}
BENCHMARK(BM_RenderLoopTickSensory);
BENCHMARK(BM_RenderLoopTickPhysical);

}  // namespace
