// Not a Google Benchmark: the tolerance Monte Carlo's wall time on the reference physical
// door with the default tolerances, per thread count, for docs/PERFORMANCE.md.
//   build/bench/doorbench_tolerance_timing [samples=200]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include "analysis/model/parameter_file.h"
#include "analysis/design/tolerance_analysis.h"

int main(int argc, char** argv) {
  const int samples = argc > 1 ? std::atoi(argv[1]) : 200;
  const doorbench::DoorModel door = doorbench::reference_model(doorbench::ModelKind::kPhysical);
  const doorbench::ToleranceSpec spec = doorbench::default_tolerances(door);
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  std::printf("%d samples, %zu toleranced parameters, %u cores\n", samples, spec.parameters.size(),
              cores);
  for (unsigned threads = 1; threads <= cores; threads *= 2) {
    doorbench::MonteCarloOptions options;
    options.samples = samples;
    options.threads = static_cast<int>(threads);
    const doorbench::ToleranceResult result = doorbench::tolerance_analysis(door, spec, options);
    std::printf("threads %u: %.2f s, %.1f ms per sample (nominal run included), %d failed\n",
                threads, result.elapsed_s, 1000.0 * result.elapsed_s / samples, result.failed);
    if (threads == cores) std::printf("%s", result.brief_report().c_str());
  }
  return 0;
}
