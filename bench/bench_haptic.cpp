// The render loop's tick: its cost alone (a device that costs nothing, records drained outside
// the timing every 50000 ticks), for the sensory and the physical reference door; and the
// simulated HapticMaster's closed loop per 1 kHz tick (docs/haptic-devices.md, "Cost").
#include <benchmark/benchmark.h>

#include "analysis/model/parameter_file.h"
#include "bench/haptic_fixed_device.h"
#include "haptic/render_loop.h"
#include "haptic/simulated_hapticmaster.h"

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

// One 1 kHz tick of the simulated HapticMaster in closed loop with the reference sensory
// door: 2.5 servo steps (hand with ±20 N pushes at 2 Hz), a read, the door's torque mapped
// to a force command. Per iteration = per tick.
void BM_SimulatedHapticMasterTick(benchmark::State& state) {
  const DoorModel model = reference_model(ModelKind::kSensory);
  const haptic::DoorMapping mapping(haptic::Kinematics::kCartesian3, haptic::ArcGeometry{},
                                    model.geometry().handle_radius_m);
  haptic::SimulatedHapticMaster device;
  haptic::SimulatedHandOptions hand;
  hand.pushes.rate_hz = 2.0;
  device.set_hand(hand, mapping);
  device.start(mapping.inertia_on_device(model.inertia_kg_m2()));
  long tick = 0;
  for (auto _ : state) {
    device.advance_to(static_cast<double>(++tick) * 0.001);
    const haptic::DeviceSample sample = device.read();
    const haptic::DoorPoint door = mapping.to_door(sample);
    device.command_force(
        mapping.to_device(model.torque_Nm(door.theta_rad, door.omega_rad_s), sample));
  }
  state.counters["servo_steps"] = static_cast<double>(device.truth().steps);
}
BENCHMARK(BM_SimulatedHapticMasterTick);

}  // namespace
