// Writes the sensory fit benchmark's data (bench/fit_benchmark_data.h: the 12 strokes, the
// truth, the 30%-off start, the bounds) to files, so that the SciPy and genetic-algorithm
// fits in studies/compare/ work on exactly what bench_fitting.cpp times. Not a timing.
//
//   doorbench_export_fit_strokes DIR [--no-fit]
//
// DIR/strokes.csv      the strokes in the CSV exchange format (door-models.md §5.1)
// DIR/setup.json       parameters (names, units, truth, start, bounds, free set), geometry,
//                      noise levels, and each stroke's id, direction and initial state
// DIR/cpp_replay.csv   each whole stroke replayed at the TRUE parameters from its first
//                      measured state under the measured force, by the fit's RK4 (2 steps
//                      per sample) and by the adaptive simulator: the reference for the
//                      Python model check (studies/compare/check_model.py)
// DIR/cpp_fit.json     fit_model's result from the start (no held-out folds, as the
//                      benchmark's first run), unless --no-fit
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

#include "analysis/fit/fit_windows.h"
#include "analysis/fit/fitting.h"
#include "analysis/simulation/simulator.h"
#include "bench/fit_benchmark_data.h"

namespace {

using namespace doorbench;
using json = nlohmann::ordered_json;

std::ofstream open_output(const std::filesystem::path& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(std::string("cannot write ").append(path.string()));
  // Enough digits that a double survives the round trip through text.
  out.precision(17);
  return out;
}

std::string direction_name(StrokeDirection direction) {
  return direction == StrokeDirection::kOpening ? "opening" : "closing";
}

void write_strokes(const PreparedData& data, const std::filesystem::path& path) {
  std::ofstream out = open_output(path);
  out << "# source: doorbench_export_fit_strokes (bench/fit_benchmark_data.h, seed 7)\n"
      << "# handle_radius_m: " << data.handle_radius_m << "\n"
      << "# sample_rate_hz: " << data.sample_rate_hz << "\n"
      << "stroke,time_s,force_N,angle_rad,rate_rad_s\n";
  for (const Stroke& stroke : data.strokes) {
    for (std::size_t i = 0; i < stroke.size(); ++i) {
      out << stroke.id << ',' << stroke.time_s[i] << ',' << stroke.force_N[i] << ','
          << stroke.theta_rad[i] << ',' << stroke.omega_rad_s[i] << '\n';
    }
  }
}

json parameter_json(const DoorModel& truth, const DoorModel& start,
                    const std::vector<std::string>& free) {
  json parameters = json::array();
  for (int i = 0; i < truth.parameter_count(); ++i) {
    const std::string& name = truth.parameter_name(i);
    const Bounds& bounds = truth.parameter_bounds()[i];
    parameters.push_back({{"name", name},
                          {"unit", std::string(truth.parameter_unit(i))},
                          {"truth", truth.parameter_values()[i]},
                          {"start", start.parameter_values()[i]},
                          {"bounds", {bounds.lower, bounds.upper}},
                          {"free", std::find(free.begin(), free.end(), name) != free.end()}});
  }
  return parameters;
}

void write_setup(const PreparedData& data, const DoorModel& truth, const DoorModel& start,
                 const std::filesystem::path& path) {
  const SyntheticStrokeOptions options = bench::fit_benchmark_stroke_options();
  json setup;
  setup["about"] =
      "The sensory fit benchmark (bench/bench_fitting.cpp): strokes in strokes.csv, "
      "parameters in the model's order; SI units, angles in rad.";
  setup["handle_radius_m"] = truth.geometry().handle_radius_m;
  setup["theta_max_rad"] = truth.geometry().theta_max_rad;
  setup["sample_rate_hz"] = data.sample_rate_hz;
  setup["seed"] = options.seed;
  setup["noise"] = {{"force_N", options.force_noise_N},
                    {"angle_rad", data.angle_noise_rad},
                    {"rate_rad_s", data.rate_noise_rad_s}};
  setup["parameters"] = parameter_json(truth, start, default_free_parameters(truth));
  json strokes = json::array();
  for (const Stroke& stroke : data.strokes) {
    strokes.push_back({{"id", stroke.id},
                       {"direction", direction_name(stroke.direction)},
                       {"samples", stroke.size()},
                       {"initial",
                        {{"time_s", stroke.time_s.front()},
                         {"angle_rad", stroke.theta_rad.front()},
                         {"rate_rad_s", stroke.omega_rad_s.front()}}}});
  }
  setup["strokes"] = strokes;
  open_output(path) << setup.dump(2) << '\n';
}

// The truth replayed over each whole stroke: the fit's RK4 and the adaptive simulator.
void write_replay(const PreparedData& data, const DoorModel& truth,
                  const std::filesystem::path& path) {
  std::ofstream out = open_output(path);
  out << "# the true parameters replayed from each stroke's first measured state\n"
      << "stroke,time_s,rk4_angle_rad,rk4_rate_rad_s,dp5_angle_rad,dp5_rate_rad_s\n";
  const int substeps = FitOptions{}.substeps_per_sample;
  for (std::size_t s = 0; s < data.strokes.size(); ++s) {
    const Stroke& stroke = data.strokes[s];
    const std::size_t n = stroke.size();
    std::vector<double> rk4_theta(n), rk4_omega(n);
    rk4_theta[0] = stroke.theta_rad[0];
    rk4_omega[0] = stroke.omega_rad_s[0];
    const FitWindow whole{static_cast<int>(s), 0, static_cast<int>(n)};
    const bool ok =
        integrate_window(truth, truth.parameter_values().data(), stroke, whole, substeps,
                         rk4_theta[0], rk4_omega[0], [&](int j, double theta, double omega) {
                           rk4_theta[j] = theta;
                           rk4_omega[j] = omega;
                         });
    if (!ok)
      throw std::runtime_error("RK4 replay of stroke " + std::to_string(stroke.id) + " ran away");
    const RecordedForce force(stroke.time_s, stroke.force_N);
    const DoorState initial{.time_s = stroke.time_s[0],
                            .theta_rad = stroke.theta_rad[0],
                            .omega_rad_s = stroke.omega_rad_s[0],
                            .user_work_J = 0.0};
    const Trajectory dp5 = simulate(truth, force, initial, stroke.time_s);
    for (std::size_t i = 0; i < n; ++i) {
      out << stroke.id << ',' << stroke.time_s[i] << ',' << rk4_theta[i] << ',' << rk4_omega[i]
          << ',' << dp5.theta_rad[i] << ',' << dp5.omega_rad_s[i] << '\n';
    }
  }
}

json error_json(const ErrorStats& stats) {
  return {{"rmse_rad_s", stats.rmse()}, {"max_abs_rad_s", stats.max_abs_error}};
}

void write_fit(const PreparedData& data, const DoorModel& truth, const DoorModel& start,
               const std::filesystem::path& path) {
  FitOptions options;
  options.cross_validation_folds = 0;  // as the benchmark's run without folds
  const auto begin = std::chrono::steady_clock::now();
  const std::clock_t cpu_begin = std::clock();  // the process's CPU time, every thread
  const FitResult result = fit_model(start, data, options);
  const double cpu_s = static_cast<double>(std::clock() - cpu_begin) / CLOCKS_PER_SEC;
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  const FitSummary& summary = result.summary;
  json fit;
  fit["about"] = "fit_model from the 30%-off start, FitOptions defaults, no held-out folds";
  fit["wall_s"] = wall_s;
  fit["cpu_s"] = cpu_s;
  fit["converged"] = summary.converged;
  fit["termination"] = summary.termination;
  fit["equation_error_iterations"] = summary.equation_error_iterations;
  fit["window_iterations"] = summary.iterations;
  fit["windows"] = summary.windows;
  json values = json::object();
  for (int i = 0; i < result.model.parameter_count(); ++i) {
    values[result.model.parameter_name(i)] = result.model.parameter_values()[i];
  }
  fit["values"] = values;
  fit["metrics"] = {{"windows", error_json(summary.fitted.window)},
                    {"replay_dp5", error_json(summary.fitted.replay)}};
  const FitMetrics at_truth = evaluate_model(truth, data, options);
  fit["metrics_at_truth"] = {{"windows", error_json(at_truth.window)},
                             {"replay_dp5", error_json(at_truth.replay)}};
  open_output(path) << fit.dump(2) << '\n';
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3 || (argc == 3 && std::string(argv[2]) != "--no-fit")) {
    std::cerr << "usage: " << argv[0] << " DIR [--no-fit]\n";
    return 2;
  }
  try {
    const std::filesystem::path dir = argv[1];
    std::filesystem::create_directories(dir);
    const PreparedData data = bench::fit_benchmark_strokes();
    const DoorModel truth = reference_model(ModelKind::kSensory);
    const DoorModel start = bench::fit_benchmark_start();
    write_strokes(data, dir / "strokes.csv");
    write_setup(data, truth, start, dir / "setup.json");
    write_replay(data, truth, dir / "cpp_replay.csv");
    if (argc == 2) write_fit(data, truth, start, dir / "cpp_fit.json");
    std::cout << "wrote " << data.strokes.size() << " strokes to " << dir.string() << "\n";
  } catch (const std::exception& error) {
    std::cerr << "export_fit_strokes: " << error.what() << "\n";
    return 1;
  }
  return 0;
}
