// One torque evaluation of each reference model (targets: sensory < 100 ns, physical
// < 300 ns), with its terms, and with derivatives.
#include <benchmark/benchmark.h>

#include <array>
#include <vector>

#include "analysis/model/parameter_file.h"

namespace {

using doorbench::DoorModel;
using doorbench::ModelKind;

// Points spread over the whole stroke, latch zones included, so that no branch is
// always predicted and no value is constant-folded.
std::vector<std::array<double, 2>> state_points() {
  std::vector<std::array<double, 2>> points;
  for (int i = 0; i < 1024; ++i) {
    const double theta = -0.01 + 1.6 * ((i * 37) % 1024) / 1024.0;
    const double omega = -2.0 + 4.0 * ((i * 91) % 1024) / 1024.0;
    points.push_back({theta, omega});
  }
  return points;
}

void torque(benchmark::State& state, ModelKind kind) {
  const DoorModel model = doorbench::reference_model(kind);
  const auto points = state_points();
  std::size_t i = 0;
  for (auto _ : state) {
    const auto& point = points[i++ & 1023];
    benchmark::DoNotOptimize(model.torque_Nm(point[0], point[1]));
  }
}

void torque_with_terms(benchmark::State& state, ModelKind kind) {
  const DoorModel model = doorbench::reference_model(kind);
  const auto points = state_points();
  std::array<double, DoorModel::kMaxTerms> terms;
  std::size_t i = 0;
  for (auto _ : state) {
    const auto& point = points[i++ & 1023];
    benchmark::DoNotOptimize(model.torque_Nm(point[0], point[1], terms));
    benchmark::ClobberMemory();
  }
}

void torque_derivatives(benchmark::State& state, ModelKind kind) {
  const DoorModel model = doorbench::reference_model(kind);
  const auto points = state_points();
  std::size_t i = 0;
  for (auto _ : state) {
    const auto& point = points[i++ & 1023];
    benchmark::DoNotOptimize(model.torque_derivatives(point[0], point[1]));
  }
}

BENCHMARK_CAPTURE(torque, sensory, ModelKind::kSensory);
BENCHMARK_CAPTURE(torque, physical, ModelKind::kPhysical);
BENCHMARK_CAPTURE(torque_with_terms, sensory, ModelKind::kSensory);
BENCHMARK_CAPTURE(torque_with_terms, physical, ModelKind::kPhysical);
BENCHMARK_CAPTURE(torque_derivatives, sensory, ModelKind::kSensory);
BENCHMARK_CAPTURE(torque_derivatives, physical, ModelKind::kPhysical);

}  // namespace
