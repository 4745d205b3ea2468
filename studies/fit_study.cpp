// A study, not a benchmark: the fit's result and CPU against --folds, with and without the global
// stage (analysis/fit/fitting.h, FitOptions::global_*), on recordings the tests' generators make
// (docs/PERFORMANCE.md). One CSV line per fit on stdout.
//
//   doorbench_fit_study [--family50 N] [--family1k N] [--robot] [--folds 0,3,4] [--truth]
//                       [--first-seed S] [--threads T] [--report]
//                       [--samples N] [--polished N] [--promising R] [--hops H]
//                       [--hop-size D] [--subsets K] [--rounds R] [--repolish N]
//                       [--uncertainty-tolerance U] [--no-reset] [--no-soft] [--soft F,F]
//                       [--no-global]
//                       [--basins]
//   --family50 N, --family1k N: N recordings drawn from the recording family (12 strokes) at
//            50 Hz and at 1 kHz (draw d has seed S + d - 1)
//   --robot: the 50 Hz, 4-stroke robot-operator recording with a load cell not tared, handle
//            at 0.8 m (fixtures/recording_family.h, robot_operator_conditions)
//   --folds: the cross-validation folds of each fit (default 0,3,4)
//   --truth: also fit each recording from the true door (as given, no start from the data)
//   --threads T: FitOptions::num_threads (default 0: every hardware thread)
//   --report: each fit's full report on stderr
//   --samples N, --polished N, --promising R, --hops H, --subsets K: the global stage's
//            FitOptions::global_samples, global_polished, global_promising_ratio, global_hops
//            and global_subsets (0: no subset refits); --hop-size D: global_hop_size;
//            --rounds R: global_rounds
//   --uncertainty-tolerance U: FitOptions::uncertainty_tolerance, the stopping rule's (every
//            solve of the fit, the global stage's included)
//   --no-reset: no reset start (FitOptions::global_reset false)
//   --no-soft: no fits with softer switches (FitOptions::global_soft_switches empty)
//   --soft F,F: FitOptions::global_soft_switches, the factors of the switches' sharpness
//   --repolish N: FitOptions::global_repolish (0: the best is not polished again)
//            --no-global: none of it
//            (FitOptions::global_search false)
//   --basins: instead of the fits, what separates the data fit's basin from the true door's
//            (basins() below); one line per probe: recording,probe,what,final_cost,fit_percent
//            ("error" and its message in the last two when the start breaks a constraint)
//
// Each fit starts as `doorbench fit` without --params does: the sensory reference door with the
// recording's handle radius, its values taken from the data (analysis/fit/fit_init.h), RK4
// steps of at most 1 ms. CPU is the process's user + system time (getrusage) over the call:
// the runs go one after another, so it is the fit's, every thread counted.
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "analysis/fit/fit_init.h"
#include "analysis/fit/fitting.h"
#include "core/number_format.h"
#include "fixtures/recording_family.h"
#include "fixtures/reference_doors.h"

using namespace doorbench;

namespace {

double process_cpu_s() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

struct Settings {
  int family50 = 0;
  int family1k = 0;
  bool robot = false;
  bool truth = false;
  std::vector<int> folds = {0, 3, 4};
  std::uint32_t first_seed = 1;
  int threads = 0;
  bool report = false;                            // --report: each fit's full report on stderr
  int samples = -1, polished = -1, subsets = -1;  // the global stage's, when given
  double promising = -1;                          // FitOptions::global_promising_ratio, given
  int hops = -1;                                  // FitOptions::global_hops, when given
  int rounds = -1;                                // FitOptions::global_rounds, when given
  int repolish = -1;                              // FitOptions::global_repolish, when given
  double hop_size = -1;                           // FitOptions::global_hop_size, when given
  double uncertainty_tolerance = -1;              // FitOptions::uncertainty_tolerance, given
  bool reset = true;                              // --no-reset: FitOptions::global_reset off
  bool soft = true;                               // --no-soft: no global_soft_switches
  std::vector<double> soft_factors;               // FitOptions::global_soft_switches, given
  bool global = true;                             // --no-global: FitOptions::global_search off
  bool basins = false;                            // --basins: the basin probes instead of fits
};

struct Case {
  std::string name;
  DoorModel truth;
  PreparedData data;
};

DoorModel data_start(const PreparedData& data) {
  const DoorModel base =
      testing::with_handle_radius(reference_model(ModelKind::kSensory), data.handle_radius_m);
  return start_from_data(data, base).model;
}

std::string values_text(const DoorModel& model) {
  std::string text;
  for (int i = 0; i < model.parameter_count(); ++i) {
    if (i > 0) text += ';';
    text += format_significant(model.parameter_values()[i], 10);
  }
  return text;
}

void fit_case(const Case& c, const Settings& s, const std::string& start_name,
              const DoorModel& start, bool from_data) {
  for (int folds : s.folds) {
    FitOptions options;
    options.substeps_per_sample = substeps_for_1ms_steps(c.data);
    options.cross_validation_folds = folds;
    options.num_threads = s.threads;
    if (!from_data) options.latch_start_from_data = false;
    if (s.samples >= 0) options.global_samples = s.samples;
    if (s.polished >= 0) options.global_polished = s.polished;
    if (s.promising > 0) options.global_promising_ratio = s.promising;
    if (s.hops >= 0) options.global_hops = s.hops;
    if (s.rounds >= 0) options.global_rounds = s.rounds;
    if (s.repolish >= 0) options.global_repolish = s.repolish;
    if (s.hop_size > 0) options.global_hop_size = s.hop_size;
    if (s.uncertainty_tolerance >= 0) options.uncertainty_tolerance = s.uncertainty_tolerance;
    if (s.subsets >= 0) options.global_subsets = s.subsets;
    options.global_reset = s.reset;
    if (!s.soft_factors.empty()) options.global_soft_switches = s.soft_factors;
    if (!s.soft) options.global_soft_switches.clear();
    options.global_search = s.global;
    const double cpu0 = process_cpu_s();
    const auto wall0 = std::chrono::steady_clock::now();
    std::string outcome;
    try {
      const FitResult result = fit_model(start, c.data, options);
      const double cpu = process_cpu_s() - cpu0;
      if (s.report) std::fprintf(stderr, "%s\n", result.summary.full_report().c_str());
      const double wall =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
      outcome = printf_text("%.3f,%.3f,%.10g,%.6g,%.6g,%d,%s", cpu, wall, result.summary.final_cost,
                            result.summary.fitted.window.fit_percent(),
                            result.summary.fitted.window.rmse(), result.summary.iterations,
                            values_text(result.model).c_str());
    } catch (const std::exception& error) {
      outcome = std::string("error,") + error.what();
    }
    std::printf("%s,%s,%d,%s\n", c.name.c_str(), start_name.c_str(), folds, outcome.c_str());
    std::fflush(stdout);
  }
}

// --basins: what separates the data fit's basin from the true door's. The data fit (global
// stage, no folds) polished again from its own values, three rounds, each from the last; from
// the data fit and from the true door's fit, each free parameter set alone to the other fit's
// value and the door polished by one start (no global stage, no start from the data); and the
// data-derived start is fitted with weaker angle residuals first (none, or σ_θ 3-100 times the
// data's), then with the data's. One line each: recording, probe, what, final cost, window FIT%.
void basins(const Case& c) {
  FitOptions options;
  options.substeps_per_sample = substeps_for_1ms_steps(c.data);
  options.cross_validation_folds = 0;
  options.what_would_determine = false;
  const FitResult data_fit = fit_model(data_start(c.data), c.data, options);
  FitOptions truth_options = options;
  truth_options.latch_start_from_data = false;
  const FitResult truth_fit = fit_model(c.truth, c.data, truth_options);
  FitOptions one_start = truth_options;
  one_start.global_search = false;
  one_start.equation_error_start = false;
  const auto line = [&](const char* probe, const std::string& what, const FitResult* fit,
                        const std::string& error) {
    std::printf("%s,%s,%s,%s\n", c.name.c_str(), probe, what.c_str(),
                fit != nullptr ? printf_text("%.10g,%.6g", fit->summary.final_cost,
                                             fit->summary.fitted.window.fit_percent())
                                     .c_str()
                               : ("error," + error).c_str());
    std::fflush(stdout);
  };
  line("fit", "from the data", &data_fit, "");
  line("fit", "from the truth", &truth_fit, "");
  // A start that breaks a constraint (θ0 < θ1 < ...) or a fit that fails is its line's error.
  const auto polish = [&](const char* probe, const std::string& what,
                          const std::vector<double>& values, const FitOptions& with) {
    try {
      const FitResult fit = fit_model(c.truth.with_parameter_values(values), c.data, with);
      line(probe, what, &fit, "");
      return std::optional<DoorModel>(fit.model);
    } catch (const std::exception& error) {
      line(probe, what, nullptr, error.what());
      return std::optional<DoorModel>();
    }
  };
  const auto values_of = [](const DoorModel& model) {
    return std::vector<double>(model.parameter_values().begin(), model.parameter_values().end());
  };
  std::vector<double> again = values_of(data_fit.model);
  for (int round = 1; round <= 3; ++round) {
    const std::optional<DoorModel> polished =
        polish("data fit polished again from its own values", printf_text("round %d", round), again,
               one_start);
    if (!polished) break;
    again = values_of(*polished);
  }
  for (std::size_t i = 0; i < data_fit.summary.parameters.size(); ++i) {
    if (!data_fit.summary.parameters[i].free) continue;
    const std::string& name = data_fit.summary.parameters[i].name;
    std::vector<double> values = values_of(data_fit.model);
    values[i] = truth_fit.model.parameter_values()[static_cast<int>(i)];
    (void)polish("data fit with one value of the truth's fit", name, values, one_start);
    values = values_of(truth_fit.model);
    values[i] = data_fit.model.parameter_values()[static_cast<int>(i)];
    (void)polish("truth's fit with one value of the data fit", name, values, one_start);
  }
  for (double factor : {0.0, 3.0, 10.0, 30.0, 100.0}) {
    FitOptions weak = options;
    weak.global_search = false;
    if (factor == 0) {
      weak.angle_residuals = false;
    } else {
      weak.angle_noise_rad = factor * c.data.angle_noise_rad;
    }
    const std::string what = factor == 0 ? std::string("no angle residuals -> the data's")
                                         : printf_text("sigma_theta x%g -> the data's", factor);
    try {
      const FitResult first = fit_model(data_start(c.data), c.data, weak);
      (void)polish("weaker angle residuals first", what, values_of(first.model), one_start);
    } catch (const std::exception& error) {
      line("weaker angle residuals first", what, nullptr, error.what());
    }
  }
}

std::vector<Case> cases(const Settings& s) {
  std::vector<Case> out;
  const DoorModel reference = reference_model(ModelKind::kSensory);
  for (int rate : {50, 1000}) {
    const int draws = rate == 50 ? s.family50 : s.family1k;
    for (int d = 0; d < draws; ++d) {
      const std::uint32_t seed = s.first_seed + static_cast<std::uint32_t>(d);
      testing::FamilyOptions family;
      family.sample_rates_hz = {static_cast<double>(rate)};
      const testing::RecordingConditions conditions = testing::draw_conditions(seed, family);
      std::string name = "family";
      name += std::to_string(rate) + "-" + std::to_string(seed);
      out.push_back({name, reference, testing::family_recording(reference, conditions, seed)});
    }
  }
  if (s.robot) {
    const DoorModel door = testing::with_handle_radius(reference, 0.8);
    out.push_back({"robot50", door,
                   testing::family_recording(door, testing::robot_operator_conditions(), 42)});
  }
  return out;
}

std::vector<double> number_list(const char* text) {
  std::vector<double> values;
  for (const char* p = text; *p != '\0';) {
    values.push_back(std::atof(p));
    const char* comma = std::strchr(p, ',');
    if (comma == nullptr) break;
    p = comma + 1;
  }
  return values;
}

std::vector<int> int_list(const char* text) {
  std::vector<int> values;
  for (double value : number_list(text)) values.push_back(static_cast<int>(value));
  return values;
}

}  // namespace

int main(int argc, char** argv) {
  Settings s;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    const bool has_value = i + 1 < argc;
    if (flag == "--report") {
      s.report = true;
    } else if (flag == "--robot") {
      s.robot = true;
    } else if (flag == "--truth") {
      s.truth = true;
    } else if (flag == "--no-reset") {
      s.reset = false;
    } else if (flag == "--no-soft") {
      s.soft = false;
    } else if (flag == "--no-global") {
      s.global = false;
    } else if (flag == "--basins") {
      s.basins = true;
    } else if (has_value && flag == "--family50") {
      s.family50 = std::atoi(argv[++i]);
    } else if (has_value && flag == "--family1k") {
      s.family1k = std::atoi(argv[++i]);
    } else if (has_value && flag == "--folds") {
      s.folds = int_list(argv[++i]);
    } else if (has_value && flag == "--first-seed") {
      s.first_seed = static_cast<std::uint32_t>(std::atoi(argv[++i]));
    } else if (has_value && flag == "--samples") {
      s.samples = std::atoi(argv[++i]);
    } else if (has_value && flag == "--hop-size") {
      s.hop_size = std::atof(argv[++i]);
    } else if (has_value && flag == "--uncertainty-tolerance") {
      s.uncertainty_tolerance = std::atof(argv[++i]);
    } else if (has_value && flag == "--rounds") {
      s.rounds = std::atoi(argv[++i]);
    } else if (has_value && flag == "--soft") {
      s.soft_factors = number_list(argv[++i]);
    } else if (has_value && flag == "--repolish") {
      s.repolish = std::atoi(argv[++i]);
    } else if (has_value && flag == "--hops") {
      s.hops = std::atoi(argv[++i]);
    } else if (has_value && flag == "--promising") {
      s.promising = std::atof(argv[++i]);
    } else if (has_value && flag == "--polished") {
      s.polished = std::atoi(argv[++i]);
    } else if (has_value && flag == "--subsets") {
      s.subsets = std::atoi(argv[++i]);
    } else if (has_value && flag == "--threads") {
      s.threads = std::atoi(argv[++i]);
    } else {
      std::fprintf(stderr, "doorbench_fit_study: unknown option '%s' (see the file's header)\n",
                   flag.c_str());
      return 2;
    }
  }
  std::printf(
      "recording,start,folds,cpu_s,wall_s,final_cost,fit_percent,window_rmse_rad_s,"
      "iterations,parameters\n");
  for (const Case& c : cases(s)) {
    std::fprintf(stderr, "%s: %s\n", c.name.c_str(), c.data.source.c_str());
    if (s.basins) {
      basins(c);
      continue;
    }
    fit_case(c, s, "data", data_start(c.data), true);
    if (s.truth) fit_case(c, s, "truth", c.truth, false);
  }
  return 0;
}
