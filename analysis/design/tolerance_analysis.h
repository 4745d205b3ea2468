#pragma once
// Manufacturing tolerances and what they do to the feel: Monte Carlo over the design's
// parameters within their tolerances, each sample's felt quantities from one simulated
// open-close (felt_quantities.h), run on a pool of threads. The result is the spread of each
// felt quantity and which tolerance matters most. docs/design-spec.md has the defaults, the
// file format and the method.
//
// Determinism: sample i draws from its own generator seeded by (seed, i), and results are
// stored by index, so the result is the same for any thread count.
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/design/felt_quantities.h"
#include "analysis/model/door_model.h"
#include "core/stop_request.h"

namespace doorbench {

enum class ToleranceDistribution { kUniform, kNormal };
std::string_view to_string(ToleranceDistribution distribution);

// ± plus_minus around the nominal value: in the parameter's unit, or percent of |nominal|.
// Uniform: anywhere in the band. Normal: the band is ±3σ (a capable process) and draws
// beyond it are drawn again.
struct ParameterTolerance {
  std::string name;
  double plus_minus = 0.0;
  bool percent = false;
  ToleranceDistribution distribution = ToleranceDistribution::kNormal;
  // The half-width in the parameter's unit for this nominal value.
  double absolute(double nominal) const;
};

struct ToleranceSpec {
  std::vector<ParameterTolerance> parameters;  // only those that vary (plus_minus > 0)
  const ParameterTolerance* find(std::string_view name) const;
};

// The defaults for the model's parameters (physical model names; effects and the sensory
// model get none): docs/design-spec.md lists them.
ToleranceSpec default_tolerances(const DoorModel& model);

// A tolerance file, a JSON object keyed by parameter name, overriding the defaults:
//   { "k_s": {"plus_minus": "5%", "distribution": "normal"},
//     "A_y": {"plus_minus": 0.0005, "distribution": "uniform"},
//     "T_h": {"plus_minus": 0} }
// plus_minus is a number (the parameter's unit) or a string "N%"; distribution defaults to
// normal; 0 fixes the parameter. The key "use_defaults": false starts from no tolerances.
// Unknown parameters or keys and bad values throw std::runtime_error naming the source and
// the key.
ToleranceSpec parse_tolerance_file(std::string_view json_text, std::string_view source,
                                   const DoorModel& model);

struct MonteCarloOptions {
  int samples = 1000;
  std::uint64_t seed = 1;
  // Sample i is drawn as sample first_sample + i (its generator seeded from (seed,
  // first_sample + i)): runs of consecutive ranges draw the doors one run of them all would.
  int first_sample = 0;
  int threads = 0;  // 0: every core (std::thread::hardware_concurrency)
  FeltOptions felt;
  // Called with 0 done as the samples begin, then now and then from worker threads
  // (serialized) with samples done and the total: counts that only grow, the last with
  // done == total.
  std::function<void(int done, int total)> progress;
  // Asked before each sample (core/stop_request.h): true ends the samples there and the
  // analysis throws StopRequested. May be empty.
  StopHook stop_requested;

  // Empty when usable, else a one-line message naming the option.
  std::string validate() const;
};

struct QuantitySpread {
  std::string name;
  double nominal = 0.0;
  double mean = 0.0, sd = 0.0, p5 = 0.0, p95 = 0.0, min = 0.0, max = 0.0;
  int count = 0;  // samples where the quantity was defined
};

struct ToleranceResult {
  std::vector<ParameterTolerance> tolerances;  // as used
  std::vector<double> nominal_values;          // of the toleranced parameters
  FeltQuantities nominal{};
  int samples = 0;
  int failed = 0;  // samples whose parameters the model refused or whose run failed
  std::string first_failure;
  std::vector<QuantitySpread> spreads;  // kFeltQuantities' order
  // explained[q][p]: the squared correlation of parameter p's draws with quantity q, the
  // share of q's variance that p explains linearly (the draws are independent).
  std::vector<std::vector<double>> explained;
  std::vector<std::string> most_important;  // per quantity: the parameter explaining most
  // Every sample's draws [sample][parameter] and felt quantities (NaN where it failed).
  std::vector<std::vector<double>> draws;
  std::vector<FeltQuantities> felt;
  int threads = 0;
  double elapsed_s = 0.0;

  std::string brief_report() const;
};

// Throws std::invalid_argument for bad options or a tolerance naming no parameter of the model.
ToleranceResult tolerance_analysis(const DoorModel& design, const ToleranceSpec& spec,
                                   const MonteCarloOptions& options = {});

}  // namespace doorbench
