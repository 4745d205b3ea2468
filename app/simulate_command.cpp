// doorbench simulate: run a door model under a recorded force or the virtual hand.
#include <cmath>
#include <iostream>
#include <memory>
#include <numbers>

#include "acquisition/session/output_file.h"
#include "acquisition/session/recording_csv.h"
#include "analysis/model/parameter_file.h"
#include "analysis/simulation/trajectory_io.h"
#include "analysis/simulation/virtual_hand.h"
#include "app/commands.h"
#include "app/hand_run.h"
#include "app/number_options.h"
#include "core/units.h"

namespace doorbench::app {

Trajectory simulate_hand(const DoorModel& model, const VirtualHandOptions& hand_options,
                         double output_rate_hz) {
  const VirtualHand hand(hand_options, model.geometry().handle_radius_m);
  const auto samples = static_cast<std::size_t>(std::floor(hand.duration_s() * output_rate_hz)) + 1;
  std::vector<double> times(samples);
  for (std::size_t i = 0; i < samples; ++i) times[i] = static_cast<double>(i) / output_rate_hz;
  Trajectory run = simulate(model, hand, DoorState{}, times);
  run.stroke.resize(samples);
  for (std::size_t i = 0; i < samples; ++i) run.stroke[i] = hand.stroke_at(times[i]);
  return run;
}

namespace {

struct SimulateOptions {
  ModelOptions model;
  std::string force_path;
  std::string hand;
  double target_deg = 80.0;
  double duration_s = 10.0;
  double rate_hz = 1000.0;
  std::string out_path;
  bool overwrite = false;
};

std::string describe(const SimulateOptions& options) {
  std::string text = "doorbench simulate --model " + options.model.model;
  if (!options.model.params_path.empty()) text += " --params " + options.model.params_path;
  if (!options.model.effects_path.empty()) text += " --effects " + options.model.effects_path;
  if (!options.force_path.empty()) return text + " --force " + options.force_path;
  return text + " --hand " + options.hand + " --target-deg " +
         format_csv_number(options.target_deg) + " --duration-s " +
         format_csv_number(options.duration_s);
}

void run_simulate(const SimulateOptions& options) {
  if (options.force_path.empty() == options.hand.empty()) {
    throw UsageError("simulate needs exactly one of --force FILE.csv and --hand open-close");
  }
  std::vector<std::filesystem::path> inputs;
  for (const std::string* input :
       {&options.force_path, &options.model.params_path, &options.model.effects_path}) {
    if (!input->empty()) inputs.emplace_back(*input);
  }
  check_output_file(options.out_path, inputs, options.overwrite);
  const DoorModel model = load_model(options.model);
  Trajectory run;
  if (!options.force_path.empty()) {
    const Recording recording = read_recording_csv(options.force_path);
    const double r_h = model.geometry().handle_radius_m;
    if (recording.handle_radius_m && std::abs(*recording.handle_radius_m - r_h) > 1e-9 * r_h) {
      throw std::runtime_error(options.force_path + ": handle_radius_m " +
                               format_csv_number(*recording.handle_radius_m) +
                               " differs from the door's " + format_csv_number(r_h) +
                               "; use a parameter file with the bench's handle radius");
    }
    run = simulate(model, recorded_force(recording), initial_state(recording), recording.time_s);
    if (recording.stroke) run.stroke = *recording.stroke;
  } else {
    // A bound on the output: 10 million samples (about 1 GB of CSV with every term).
    constexpr double kMaxSamples = 1e7;
    if (options.duration_s * options.rate_hz > kMaxSamples) {
      throw UsageError("--duration-s " + format_csv_number(options.duration_s) + " at --rate-hz " +
                       format_csv_number(options.rate_hz) + " gives " +
                       format_csv_number(options.duration_s * options.rate_hz) +
                       " samples; at most 10000000");
    }
    VirtualHandOptions hand;
    hand.target_angle_rad = options.target_deg * kRadPerDeg;
    hand.duration_s = options.duration_s;
    run = simulate_hand(model, hand, options.rate_hz);
  }
  write_recording_csv_file(options.out_path, to_recording(run, describe(options)));
  std::cerr << "wrote " << run.size() << " samples to " << options.out_path << " ("
            << run.stats.accepted_steps << " steps, smallest " << run.stats.smallest_step_s
            << " s)\n";
}

}  // namespace

void add_simulate_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<SimulateOptions>();
  CLI::App* simulate = app.add_subcommand(
      "simulate",
      "Integrate J domega/dt = tau_u + tau_m(theta, omega) under a recorded handle force or a "
      "virtual hand, and write the run in the CSV exchange format plus every term's torque.");
  add_model_options(*simulate, options->model);
  auto* force = simulate->add_option(
      "--force", options->force_path,
      "Recording (CSV exchange format) whose force_N drives the door from its first state");
  auto* hand =
      simulate
          ->add_option("--hand", options->hand,
                       "Virtual hand: a PD controller on the handle tracking rest, a minimum-jerk "
                       "opening, a pause and a closing")
          ->check(CLI::IsMember({"open-close"}));
  force->excludes(hand);
  simulate->add_option("--target-deg", options->target_deg, "Virtual hand: opening target (deg)")
      ->check(number_range(0.1, 180.0))
      ->capture_default_str();
  simulate->add_option("--duration-s", options->duration_s, "Virtual hand: whole run (s)")
      ->check(number_range(0.5, 3600.0))
      ->capture_default_str();
  simulate->add_option("--rate-hz", options->rate_hz, "Virtual hand: output sample rate (Hz)")
      ->check(number_range(1.0, 100000.0))
      ->capture_default_str();
  simulate->add_option("--out", options->out_path, "Where to write the run (CSV)")->required();
  simulate->add_flag("--overwrite", options->overwrite, "Replace an existing --out file");
  simulate->callback([options, &action] { action = [options] { run_simulate(*options); }; });
}

}  // namespace doorbench::app
