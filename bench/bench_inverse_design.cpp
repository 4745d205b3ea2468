// The inverse design of `doorbench spec` on one 19 s bench recording (the prototype door of
// docs/inverse-design.md: the reference door with the spring preload F0 −12 % and the hinge
// friction T_h +25 %, recorded through the simulated bench's sensors as `doorbench record` records
// it), against the reference door's file. Target: under 20 s wall on 2 cores (docs/PERFORMANCE.md).
//   build/bench/doorbench_inverse_design_bench [--benchmark_filter=Sparse]
#include <benchmark/benchmark.h>

#include "analysis/design/inverse_design.h"
#include "analysis/model/parameter_file.h"
#include "fixtures/bench_recorded_door.h"
#include "fixtures/temp_dir.h"

namespace {

const doorbench::PreparedData& recording() {
  static const doorbench::PreparedData data = [] {
    const doorbench::testing::TempDir dir("inverse_design_bench");
    const doorbench::DoorModel reference =
        doorbench::reference_model(doorbench::ModelKind::kPhysical);
    return doorbench::testing::record_bench_door(
        doorbench::testing::with_factors(reference, {{"F0", 0.88}, {"T_h", 1.25}}),
        dir.path / "tobe.h5");
  }();
  return data;
}

void run(benchmark::State& state, const doorbench::InverseDesignOptions& options) {
  const doorbench::DoorModel asis = doorbench::reference_model(doorbench::ModelKind::kPhysical);
  const doorbench::PreparedData& data = recording();
  int fits = 0;
  double sparse_s = 0.0;
  doorbench::FitSummary::Times times;
  for (auto _ : state) {
    const doorbench::InverseDesignResult result = doorbench::inverse_design(asis, {data}, options);
    fits = result.fits_run;
    sparse_s = result.sparse_search_s;
    times = result.fit_times;
    benchmark::DoNotOptimize(result.solutions.size());
  }
  state.counters["fits"] = fits;
  state.counters["sparse_search_s"] = sparse_s;  // the rest: the smallest change beside it
  // Where the fits' time went (summed over the fits of the last iteration).
  state.counters["eq_error_s"] = times.equation_error_s;
  state.counters["windows_s"] = times.windows_s;
  state.counters["statistics_s"] = times.statistics_s;
  state.counters["metrics_s"] = times.metrics_s;
  state.counters["setup_s"] = times.start_s;
}

// `doorbench spec`'s default: the sparse search, the smallest change beside it (one start).
void BM_InverseDesignSparse(benchmark::State& state) {
  run(state, doorbench::InverseDesignOptions{});
}
BENCHMARK(BM_InverseDesignSparse)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(3);

// The smallest change from 3 starts in two passes, then 10 fewest-changes refits (the
// playback path's inverse design), for comparison with `doorbench spec`'s.
void BM_InverseDesignSmallestChangeAndFewest(benchmark::State& state) {
  doorbench::InverseDesignOptions options;
  options.sparse_search = false;
  run(state, options);
}
BENCHMARK(BM_InverseDesignSmallestChangeAndFewest)
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

}  // namespace
