// doorbench demo: the main job on the simulated bench. The reference door opened and
// closed by the virtual hand with both models, a summary each, the runs on disk; a
// session recorded on the simulated bench; its sensors calibrated (app/calibration_demo.h);
// and the residual loop closed on a recording
// whose door has an effect the sensory model does not declare.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>

#include "acquisition/session/output_file.h"
#include "acquisition/session/recording_csv.h"
#include "acquisition/session/session_csv.h"
#include "analysis/design/specify.h"
#include "analysis/fit/fitting.h"
#include "analysis/loop/residual_loop.h"
#include "analysis/model/parameter_file.h"
#include "analysis/preprocessing/preprocessing.h"
#include "analysis/report/svg_plot.h"
#include "analysis/simulation/run_summary.h"
#include "analysis/simulation/trajectory_io.h"
#include "app/calibration_demo.h"
#include "app/campaign_report.h"
#include "app/commands.h"
#include "app/hand_run.h"
#include "app/loop_output.h"
#include "app/play_run.h"
#include "app/session_recording.h"
#include "core/units.h"
#include "sensors/sensor_models.h"

namespace doorbench::app {
namespace {

struct DemoOptions {
  std::string out_dir = "doorbench-demo";
};

// The samples of one stroke (1 opening, 2 closing) below an angle, as degrees and newtons.
struct Curve {
  std::vector<double> angle_deg, force_N;
};

Curve latch_curve(const Trajectory& run, int stroke, double below_deg) {
  Curve curve;
  for (std::size_t i = 0; i < run.size(); ++i) {
    const double angle_deg = run.theta_rad[i] * kDegPerRad;
    if (run.stroke[i] == stroke && angle_deg < below_deg) {
      curve.angle_deg.push_back(angle_deg);
      curve.force_N.push_back(run.force_N[i]);
    }
  }
  return curve;
}

struct ModelRun {
  ModelKind kind;
  Trajectory run;
  std::vector<double> angle_deg;
};

void write_plots(const std::filesystem::path& dir, const std::vector<ModelRun>& runs) {
  std::vector<PlotSeries> angle, force, loops;
  std::vector<Curve> curves;
  curves.reserve(2 * runs.size());
  for (const ModelRun& model_run : runs) {
    const std::string name(to_string(model_run.kind));
    angle.push_back({.label = name + " model",
                     .x = model_run.run.time_s,
                     .y = model_run.angle_deg,
                     .color = ""});
    force.push_back({.label = name + " model",
                     .x = model_run.run.time_s,
                     .y = model_run.run.force_N,
                     .color = ""});
    curves.push_back(latch_curve(model_run.run, 1, 8.0));
    curves.push_back(latch_curve(model_run.run, 2, 8.0));
  }
  const char* colors[] = {"#1f77b4", "#6baed6", "#d62728", "#fc9272"};
  for (std::size_t i = 0; i < curves.size(); ++i) {
    const std::string name(to_string(runs[i / 2].kind));
    loops.push_back({.label = name + (i % 2 == 0 ? ", opening" : ", closing"),
                     .x = curves[i].angle_deg,
                     .y = curves[i].force_N,
                     .color = colors[i % 4]});
  }
  write_svg_plot((dir / "angle.svg").string(),
                 {"Door angle, virtual hand open-close", "time (s)", "angle (deg)"}, angle);
  write_svg_plot((dir / "hand-force.svg").string(),
                 {"Hand force at the handle (positive = opening)", "time (s)", "force (N)"}, force);
  write_svg_plot(
      (dir / "force-angle-latch.svg").string(),
      {"Force-angle near closed: unlatching and latching", "angle (deg)", "hand force (N)"}, loops);
}

// The rig's gyroscope range (°/s): its channel's range_dps, or the sensor model's default.
double gyro_range_dps(const RigDefinition& rig) {
  double range_dps = GyroscopeParameters{}.range_dps;
  for (const RigChannel& channel : rig.channels) {
    if (channel.sensor != "gyroscope") continue;
    for (const auto& [name, value] : channel.parameters) {
      if (name == "range_dps") range_dps = value;
    }
  }
  return range_dps;
}

// Records the built-in simulated bench into DIR/session.h5, exports it as CSV and compares
// what the sensors measured with the simulator's truth.
void record_demo_session(const std::filesystem::path& dir) {
  const std::filesystem::path session_path = dir / "session.h5";
  const std::filesystem::path csv_path = dir / "session.csv";
  // The demo owns its folder: a session from an earlier demo run is replaced.
  std::filesystem::remove(session_path);
  const RigDefinition rig = load_rig("");
  SessionRecordingOptions options;
  options.operator_name = "doorbench demo";
  options.product_id = "reference dishwasher door (simulated)";
  options.show_progress = false;
  const RecordSummary summary = record_simulated_session(rig, options, session_path);
  const SessionReader session(session_path);
  const Recording exported = session_to_recording(session);
  write_recording_csv_file(csv_path, exported);

  const std::vector<double> truth_force = session.read_group_dataset("truth", "force_N");
  const std::vector<double> truth_rate = session.read_group_dataset("truth", "omega_rad_s");
  // The hand only pushes the compression-only load cell; compare where the truth presses on
  // it by more than 1 N (below, the cell's noise and hysteresis dominate). The demo's strokes
  // alternate from an opening: odd ids open (+F_u presses), even ids close (−F_u).
  double force_sq = 0.0, rate_sum = 0.0, rate_sq = 0.0, fastest_dps = 0.0, first_beyond_s = 0.0;
  std::size_t force_n = 0, saturated = 0, stretches = 0;
  bool beyond_before = false;
  const double gyro_limit_dps = gyro_range_dps(rig);
  const std::size_t n = std::min(exported.size(), truth_force.size());
  for (std::size_t i = 0; i < n; ++i) {
    const int stroke = exported.stroke ? (*exported.stroke)[i] : 0;
    const double mounting = stroke % 2 == 1 ? 1.0 : -1.0;
    if (stroke != 0 && truth_force[i] * mounting > 1.0) {
      force_sq += std::pow(exported.force_N[i] - truth_force[i], 2);
      ++force_n;
    }
    // The door falls open faster than the gyroscope's range: those samples are clipped.
    const double rate_dps = std::abs(truth_rate[i]) * kDegPerRad;
    fastest_dps = std::max(fastest_dps, rate_dps);
    const bool beyond = rate_dps >= gyro_limit_dps;
    if (beyond && !beyond_before && stretches++ == 0) first_beyond_s = exported.time_s[i];
    beyond_before = beyond;
    if (beyond) {
      ++saturated;
      continue;
    }
    const double rate_error = (*exported.rate_rad_s)[i] - truth_rate[i];
    rate_sum += rate_error;
    rate_sq += rate_error * rate_error;
  }
  const std::size_t rate_n = std::max<std::size_t>(n - saturated, 1);
  const double rate_mean = rate_sum / rate_n;
  const double rate_spread = std::sqrt(std::max(0.0, rate_sq / rate_n - rate_mean * rate_mean));
  int strokes = 0;
  for (const SessionEvent& event : session.events()) strokes += event.kind == "stroke_start";
  std::cout << "\nsimulated session (" << session_path.string() << "): rig " << rig.name << ", "
            << rig.channels.size() << " channels, " << summary.scans << " scans ("
            << summary.duration_s << " s), " << strokes << " strokes\n";
  std::printf(
      "  measured vs truth: force %.2f N RMS where the hand presses the load cell; rate off by "
      "%.2f deg/s (the gyroscope's bias) with %.3f deg/s of noise\n",
      std::sqrt(force_sq / std::max<std::size_t>(force_n, 1)), rate_mean * kDegPerRad,
      rate_spread * kDegPerRad);
  if (saturated > 0) {
    std::printf(
        "  outside the sensors' ranges: the door turns faster than the gyroscope's ±%g deg/s in "
        "%zu stretches (%zu samples, up to %.0f deg/s, the first at %.2f s): the physical door "
        "falls open by its weight faster than the virtual hand holds it back (the hand's push "
        "is limited) and runs to its open stop; the rate there is clipped, so fit, loop and view "
        "leave those samples out and the overlay shades them\n",
        gyro_limit_dps, stretches, saturated, fastest_dps, first_beyond_s);
  } else {
    std::printf("  inside the gyroscope's ±%g deg/s throughout (up to %.0f deg/s)\n",
                gyro_limit_dps, fastest_dps);
  }
  std::cout << "  exported to " << csv_path.string() << " (doorbench info " << session_path.string()
            << " shows the session)\n";
}

// The effect the demo's door has and the sensory model does not declare: a weight that
// pulls the door open, g1 sin θ with g1 = 3 N·m (door-models.md §4, gravity_imbalance).
constexpr const char* kUndeclaredEffectJson = R"({"gravity_imbalance": {"g1": 3.0}})";

// Records the reference door with the undeclared effect on the simulated bench, fits the
// sensory model and runs the residual loop; prints the table of steps.
DoorModel close_the_loop(const std::filesystem::path& dir) {
  const std::filesystem::path effects_path =
      std::filesystem::absolute(dir / "undeclared-effect.json");
  std::ofstream(effects_path) << kUndeclaredEffectJson << "\n";
  RigDefinition rig = load_rig("");
  rig.simulation->model = "sensory";
  rig.simulation->effects = effects_path.string();
  const std::filesystem::path session_path = dir / "undeclared-effect.h5";
  std::filesystem::remove(session_path);
  SessionRecordingOptions recording;
  recording.operator_name = "doorbench demo";
  recording.product_id = "reference door with an undeclared gravity imbalance (simulated)";
  recording.show_progress = false;
  record_simulated_session(rig, recording, session_path);
  std::cout << "\nclosing the loop: the door of " << session_path.string()
            << " has an effect the sensory model does not declare (" << kUndeclaredEffectJson
            << "); fitting the sensory model and running the residual loop\n";
  const PreparedData data = prepare_session(session_path);
  LoopOptions options;
  options.progress = [](const std::string& line) { std::cout << "  " << line << std::endl; };
  const LoopResult loop = run_residual_loop(reference_model(ModelKind::kSensory), data, options);
  const std::filesystem::path loop_dir = dir / "loop";
  std::filesystem::create_directories(loop_dir);
  const std::string table = write_loop_outputs(loop_dir, loop, data, "sensory", options.fit);
  std::cout << loop.brief_report() << "\n"
            << table << "  (report: " << (loop_dir / "report.md").string() << ")\n";
  return loop.model();
}

// A playback for measurement on the simulated HapticMaster: 30 s of simulated time, the virtual
// user opening and closing the door every 10 s, and the device's own force and force-rate
// limits (the virtual user pushes the door into its closed stop, and a force the safety layer
// clipped is a force a fit would not see: docs/haptic.md).
PlayRequest measurement_playback(const std::filesystem::path& session_path,
                                 const std::string& model_source) {
  std::filesystem::remove(session_path);
  PlayRequest request;
  request.device.uri = "sim";
  request.device.simulated_time = true;
  request.device.hand.duration_s = 10.0;
  request.playback.duration_s = 30.0;
  request.playback.loop.safety.max_force = 100.0;
  request.playback.loop.safety.max_force_rate = 20000.0;
  request.session_path = session_path;
  request.model_source = model_source;
  request.operator_name = "doorbench demo";
  request.show_status = false;
  return request;
}

// Plays the loop's fitted door on the simulated HapticMaster with the virtual user opening and
// closing it, records it, and fits the recording back from the reference door (with the same
// effects at their catalogue defaults): the played parameters should come back.
void play_and_fit_back(const std::filesystem::path& dir, const DoorModel& fitted) {
  const std::filesystem::path session_path = dir / "haptic-playback.h5";
  const PlayRequest request = measurement_playback(
      session_path, "the residual loop's fitted door (" + (dir / "loop").string() + ")");
  std::cout << "\nhaptic playback: the fitted door on the simulated HapticMaster (admittance, 1 ms "
               "control delay, force-sensor noise), the virtual user opening and closing it "
               "three times; 30 s at 1 kHz in simulated time\n";
  const haptic::PlaybackSummary summary = play_model(fitted, request);
  std::cout << "  " << summary.brief_report() << "\n";
  std::vector<EffectSetting> start_effects;
  for (const EffectSetting& effect : fitted.effects()) {
    EffectSetting setting{effect.kind, {}, effect.bounds};
    for (const effects::EffectParameter& parameter : effects::info(effect.kind).parameters) {
      setting.values.push_back(parameter.default_value);
    }
    start_effects.push_back(std::move(setting));
  }
  const DoorModel reference = reference_model(ModelKind::kSensory);
  const auto values = reference.parameter_values();
  const auto bounds = reference.parameter_bounds();
  const DoorModel start(ModelKind::kSensory, reference.geometry(),
                        std::vector<double>(values.begin(), values.end()),
                        std::vector<Bounds>(bounds.begin(), bounds.end()), start_effects);
  const PreparedData data = prepare_session(session_path);
  FitOptions fit_options;
  fit_options.cross_validation_folds = 0;
  const FitResult fit = fit_model(start, data, fit_options);
  std::cout << "  fitted back (" << data.strokes.size() << " strokes, from the reference door):\n"
            << "    parameter          played      recovered   u           change\n";
  for (const FittedParameter& parameter : fit.summary.parameters) {
    if (!parameter.free) continue;
    const double played = fitted.parameter_values()[*fitted.find_parameter(parameter.name)];
    char line[160];
    std::snprintf(line, sizeof line, "    %-18s %-11.5g %-11.5g %-11.3g %+.2f%%\n",
                  parameter.name.c_str(), played, parameter.value, parameter.uncertainty,
                  100.0 * (parameter.value - played) / std::abs(played));
    std::cout << line;
  }
}

// The study's last step, on a door whose answer is known: the AS-IS physical door (the
// reference door's physical model) tuned 30 % easier to unlatch (latch spring and preload
// x0.7) and 20 % heavier (J_d x1.2), played on the simulated HapticMaster and recorded as the
// TO-BE feel; the specification then says what to change on the AS-IS door, and the demo
// prints it beside what was played.
void specify_tuned_variant(const std::filesystem::path& dir) {
  const DoorModel asis = reference_model(ModelKind::kPhysical);
  std::vector<double> values(asis.parameter_values().begin(), asis.parameter_values().end());
  for (const char* name : {"k_l", "F_l0"}) values[*asis.find_parameter(name)] *= 0.7;
  values[*asis.find_parameter("J_d")] *= 1.2;
  const DoorModel tuned = asis.with_parameter_values(values);
  const std::filesystem::path session_path = dir / "tobe-tuned.h5";
  const PlayRequest request = measurement_playback(
      session_path, "the AS-IS physical door tuned: k_l and F_l0 x0.7, J_d x1.2");
  std::cout << "\nthe TO-BE feel: the AS-IS physical door tuned 30 % easier to unlatch (k_l, F_l0 "
               "x0.7) and 20 % heavier (J_d x1.2), played on the simulated HapticMaster and "
               "recorded (30 s)\n";
  std::cout << "  " << play_model(tuned, request).brief_report() << "\n";
  std::cout << "\nthe design specification: the AS-IS physical door ("
            << (dir / "physical-params.json").string()
            << ") changed as little as possible to feel like the TO-BE recording (J_d left free: "
               "the variant is heavier). The playback recorded the torque it commanded, so the "
               "design is fitted to that torque (the device's rendering is not in it) and the "
               "inertia to the recorded motion\n";
  SpecOptions spec;
  spec.tobe_paths = {session_path};
  spec.asis_path = dir / "physical-params.json";
  spec.out_dir = dir / "spec";
  spec.fixed = std::vector<std::string>{"m_d", "l_c", "k_stop", "c_stop", "e", "w_f"};
  spec.overwrite = true;  // the demo owns its folder
  spec.command = "doorbench spec " + session_path.string() + " --asis " + spec.asis_path.string() +
                 " --out " + spec.out_dir.string() +
                 " --fixed m_d,l_c,k_stop,c_stop,e,w_f --samples 1000 --seed 1";
  std::cout << specify(spec).brief_report();
  const DoorModel specified =
      load_model(ModelKind::kPhysical, dir / "spec" / "tobe-params.json", "");
  std::cout << "  played vs specified (the changed parameters; the inertia comes from the motion, "
               "where the device's own dynamics add a little):\n";
  for (const char* name : {"J_d", "k_l", "F_l0"}) {
    const int index = *asis.find_parameter(name);
    const double played = tuned.parameter_values()[index];
    const double value = specified.parameter_values()[index];
    char line[200];
    std::snprintf(line, sizeof line,
                  "    %-6s AS-IS %-10.5g played %-10.5g specified %-10.5g (%+.1f %% of played)\n",
                  name, asis.parameter_values()[index], played, value,
                  100.0 * (value - played) / std::abs(played));
    std::cout << line;
  }
}

void run_demo(const DemoOptions& options) {
  const std::filesystem::path dir = options.out_dir;
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) throw std::runtime_error(dir.string() + ": cannot create folder: " + error.message());
  std::cout << "doorbench demo: the reference door on the simulated bench, opened to 80 deg and "
               "closed again by the virtual hand (10 s at 1 kHz)\n";
  std::vector<ModelRun> runs;
  for (ModelKind kind : {ModelKind::kSensory, ModelKind::kPhysical}) {
    const DoorModel model = reference_model(kind);
    const Trajectory& run =
        runs.emplace_back(ModelRun{kind, simulate_hand(model, VirtualHandOptions{}, 1000.0), {}})
            .run;
    const std::filesystem::path run_path = dir / (std::string(to_string(kind)) + "-open-close.csv");
    write_recording_csv_file(
        run_path, to_recording(run, "doorbench demo, reference door, " +
                                        std::string(to_string(kind)) + " model, virtual hand"));
    const std::filesystem::path params_path = dir / (std::string(to_string(kind)) + "-params.json");
    write_text_file_atomically(params_path, to_parameter_json(model));
    std::cout << "\n"
              << to_string(kind) << " model (" << run_path.string() << "):\n"
              << format_summary(summarize_run(model, run));
  }
  for (ModelRun& model_run : runs) {
    for (double theta : model_run.run.theta_rad) model_run.angle_deg.push_back(theta * kDegPerRad);
  }
  write_plots(dir, runs);
  record_demo_session(dir);
  std::cout << "\n";
  run_calibration_demo(std::cout);
  const DoorModel fitted = close_the_loop(dir);
  play_and_fit_back(dir, fitted);
  specify_tuned_variant(dir);
  run_demo_campaign(dir / "campaign", std::cout);
  analyze_demo_campaign(dir / "campaign", dir / "physical-params.json", std::cout);
  std::cout << "\nruns, parameter files and plots (angle.svg, hand-force.svg, "
               "force-angle-latch.svg) are in "
            << dir.string() << "/\n";
}

}  // namespace

void add_demo_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<DemoOptions>();
  CLI::App* demo = app.add_subcommand(
      "demo", "Run the main job on the simulated bench (no hardware needed) and summarize it");
  demo->add_option("--out", options->out_dir, "Folder for the runs")->capture_default_str();
  demo->callback([options, &action] { action = [options] { run_demo(*options); }; });
}

}  // namespace doorbench::app
