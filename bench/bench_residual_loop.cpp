// The whole residual loop (analysis/loop/residual_loop.h), default options, wall clock:
//   residual_loop_demo: the demo's recording (docs/residual-loop.md, "On a bench recording"):
//     the sensory reference door with an undeclared gravity imbalance g1 = 3 N·m recorded on
//     the simulated bench for 19 s (seed 1, 6 strokes), through the session file and
//     preprocessing; the loop adds the imbalance and stops. Target: < 5 s.
//   residual_loop_tremor_12_strokes/<effect>: 12 strokes of the tremor hand
//     (fixtures/tremor_recording.h, seed 1); 0 clean, 1 breakaway friction (d_s − d1 = 1.5
//     N·m, w_s = 0.05 rad/s), 2 gravity imbalance g1 = 3 N·m. Target: < 10 s on 2 cores.
// Counters: fit_model calls, effects added, strokes, and process_cpu_s: the CPU time of the
// whole process (every thread: the refits', the folds' and Ceres' own), user + system.
// Each iteration is a whole loop (seconds to a minute): run with --benchmark_min_time=0.
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <filesystem>
#include <fstream>

#include "analysis/loop/residual_loop.h"
#include "analysis/model/parameter_file.h"
#include "analysis/preprocessing/preprocessing.h"
#include "fixtures/simulated_session.h"
#include "fixtures/temp_dir.h"
#include "fixtures/tremor_recording.h"

namespace {

using namespace doorbench;

const PreparedData& demo_recording() {
  static const PreparedData data = [] {
    const testing::TempDir dir("bench_residual_loop");
    const auto effects_path = dir / "undeclared.json";
    std::ofstream(effects_path) << R"({"gravity_imbalance": {"g1": 3.0}})"
                                << "\n";
    const auto session_path = dir / "demo.h5";
    testing::record_built_in_session(session_path, 19.0, 1, "sensory", effects_path);
    return prepare_session(session_path);
  }();
  return data;
}

DoorModel with_effect(const DoorModel& model, effects::Kind kind, std::vector<double> values) {
  EffectSetting setting{kind, std::move(values), {}};
  for (const effects::EffectParameter& p : effects::info(kind).parameters) {
    setting.bounds.push_back(p.default_bounds);
  }
  return model.with_effect(std::move(setting));
}

PreparedData tremor_recording(int effect) {
  const DoorModel sensory = reference_model(ModelKind::kSensory);
  const double d1 = sensory.parameter_values()[*sensory.find_parameter("d1")];
  DoorModel truth = sensory;
  if (effect == 1) truth = with_effect(sensory, effects::Kind::kStribeck, {d1 + 1.5, 0.05});
  if (effect == 2) truth = with_effect(sensory, effects::Kind::kGravityImbalance, {3.0});
  testing::TremorRecordingOptions options;
  options.seed = 1;
  return testing::tremor_recording(truth, options);
}

double process_cpu_s() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  auto seconds = [](const timeval& t) { return t.tv_sec + 1e-6 * t.tv_usec; };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

void run_loop(benchmark::State& state, const PreparedData& data) {
  const DoorModel start = reference_model(ModelKind::kSensory);
  int fits = 0;
  std::size_t added = 0;
  const double cpu_before_s = process_cpu_s();
  for (auto _ : state) {
    const LoopResult loop = run_residual_loop(start, data, LoopOptions{});
    fits = loop.fits;
    added = loop.steps.size();
    benchmark::DoNotOptimize(loop.steps.data());
  }
  state.counters["fits"] = fits;
  state.counters["effects_added"] = static_cast<double>(added);
  state.counters["strokes"] = static_cast<double>(data.strokes.size());
  state.counters["process_cpu_s"] =
      (process_cpu_s() - cpu_before_s) / static_cast<double>(state.iterations());
}

void residual_loop_demo(benchmark::State& state) {
  run_loop(state, demo_recording());
}

void residual_loop_tremor_12_strokes(benchmark::State& state) {
  const PreparedData data = tremor_recording(static_cast<int>(state.range(0)));
  run_loop(state, data);
}

}  // namespace

BENCHMARK(residual_loop_demo)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);
BENCHMARK(residual_loop_tremor_12_strokes)
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);
