// doorbench play: a door model rendered on a haptic device, every tick recorded as a session.
#include <unistd.h>

#include <iostream>
#include <memory>
#include <string>
#include <string_view>

#include "acquisition/session/output_file.h"
#include "analysis/model/parameter_file.h"
#include "app/commands.h"
#include "app/fit_inputs.h"
#include "app/number_options.h"
#include "app/play_run.h"
#include "app/station_screen.h"
#include "core/number_format.h"
#include "study/tuning_keys.h"

namespace doorbench::app {
namespace {

struct PlayOptions {
  ModelOptions model;
  std::string device = "sim";
  std::string out;
  double duration_s = 20.0;
  double rate_hz = 1000.0;
  bool simulated_time = false;
  bool no_fifo = false;
  double hand_cycle_s = 10.0;
  double pushes_hz = 0.0;
  double push_N = 20.0;
  std::uint64_t seed = 1;
  std::string watch_params;
  double max_force_N = 60.0;
  double max_force_rate_N_per_s = 5000.0;
  double max_tick_interval_ms = 5.0;
  double max_tick_stall_ms = 100.0;
  bool keys = false;
  StationCommandOptions station;
};

// Live tuning from the keypad (study/tuning_keys.h): every key press moves one perceptual
// control; an applied change is played from the next tick, and every press (refused ones
// too) becomes a "tuning" event of the session.
class KeypadTuning {
 public:
  explicit KeypadTuning(const DoorModel& start)
      : keys_(STDIN_FILENO, "stdin"), tuner_(start, "start") {
    std::cerr << "tuning keys (the session records every press):\n" << study::key_map_text();
  }

  void poll(haptic::Playback& playback) {
    while (const std::optional<char> key = keys_.poll(0.0)) {
      const double time_s = playback.loop().status().time_s;
      const study::TuningLogEntry& entry = tuner_.press(*key, time_s);
      std::string outcome = entry.message;
      if (entry.applied) {
        const std::string description =
            std::string("key ").append(1, *key).append(": ").append(entry.message);
        const std::string problem = playback.change_parameters(tuner_.model(), description);
        if (!problem.empty()) outcome = "not played: " + problem;
      }
      playback.recorder().add_event(
          {.time_s = time_s,
           .kind = "tuning",
           .channel = "",
           .detail = std::string("key ").append(1, *key).append(": ").append(outcome)});
      std::cerr << "\nkey " << *key << ": " << outcome << "\n";
    }
  }

 private:
  study::TerminalKeys keys_;
  study::KeyTuner tuner_;
};

// Live tuning from another program (the viewer's tuning layout saves a parameter file): when
// the watched file changes, its base section replaces the playing model's (the effects stay).
class ParameterFileWatcher {
 public:
  explicit ParameterFileWatcher(std::string path) : path_(std::move(path)) {
    std::error_code error;
    if (!path_.empty()) last_ = std::filesystem::last_write_time(path_, error);
    if (error) last_ = std::filesystem::file_time_type::min();
  }

  void poll(haptic::Playback& playback) {
    if (path_.empty() || !changed()) return;
    try {
      const DoorModel& current = playback.current_model();
      const DoorModel base = load_model(current.kind(), path_, "");
      const auto values = base.parameter_values();
      const auto bounds = base.parameter_bounds();
      std::vector<EffectSetting> effects(current.effects().begin(), current.effects().end());
      const DoorModel next(current.kind(), current.geometry(),
                           std::vector<double>(values.begin(), values.end()),
                           std::vector<Bounds>(bounds.begin(), bounds.end()), effects);
      const std::string problem = playback.change_parameters(next, "file " + path_);
      if (problem.empty()) {
        std::cerr << "\n"
                  << path_ << ": applied as parameter set "
                  << playback.loop().mailbox().next_id() - 1 << "\n";
      } else {
        std::cerr << "\n" << path_ << ": not applied: " << problem << "\n";
      }
    } catch (const std::exception& error) {
      std::cerr << "\n" << path_ << ": not applied: " << error.what() << "\n";
    }
  }

 private:
  // True when the file's modification time differs from the last seen (created, rewritten).
  bool changed() {
    std::error_code error;
    const auto time = std::filesystem::last_write_time(path_, error);
    if (error || time == last_) return false;
    last_ = time;
    return true;
  }
  std::string path_;
  std::filesystem::file_time_type last_{};
};

// --device's form, before anything is read or opened: a usage error (exit 2) naming the
// devices there are (haptic/device_factory.h opens them).
void check_device(const std::string& uri) {
  if (uri == "sim" || uri == "sim:hapticmaster" || uri == "sim:rotary") return;
  constexpr std::string_view kHapticMaster = "hapticmaster://";
  if (uri.starts_with(kHapticMaster)) {
    if (uri.size() > kHapticMaster.size()) return;
    throw UsageError("--device '" + uri + "': no host (hapticmaster://HOST[:PORT])");
  }
  throw UsageError("--device '" + uri +
                   "': not a device (use sim, sim:hapticmaster, sim:rotary or "
                   "hapticmaster://HOST[:PORT])");
}

void run_play(const PlayOptions& options) {
  check_device(options.device);
  const DoorModel model =
      start_model(options.model.model, options.model.params_path, options.model.effects_path);
  PlayRequest request;
  request.device.uri = options.device;
  request.device.simulated_time = options.simulated_time;
  request.device.hand.duration_s = options.hand_cycle_s;
  request.device.pushes.rate_hz = options.pushes_hz;
  request.device.pushes.amplitude_N = options.push_N;
  request.device.seed = options.seed;
  request.playback.duration_s = options.duration_s;
  request.playback.loop.rate_hz = options.rate_hz;
  request.playback.real_time.request_fifo = !options.no_fifo;
  if (options.no_fifo) request.device.hapticmaster.io_fifo_priority = 0;
  request.playback.loop.safety.max_force = options.max_force_N;
  request.playback.loop.safety.max_force_rate = options.max_force_rate_N_per_s;
  request.playback.loop.safety.max_tick_interval_s = 1e-3 * options.max_tick_interval_ms;
  request.playback.loop.safety.max_tick_stall_s = 1e-3 * options.max_tick_stall_ms;
  request.device.hapticmaster.command_watchdog_s = 1e-3 * options.max_tick_stall_ms;
  request.device.hapticmaster.progress = [](const std::string& line) { std::cerr << line << "\n"; };
  request.session_path = options.out;
  request.model_source =
      options.model.params_path.empty() ? "reference door" : options.model.params_path;
  request.effects = options.model.effects_path;
  std::vector<std::filesystem::path> inputs;
  for (const std::string* input : {&options.model.params_path, &options.model.effects_path}) {
    if (!input->empty()) inputs.emplace_back(*input);
  }
  check_output_session(request.session_path, inputs);
  std::cerr << "playing the " << to_string(model.kind()) << " model (" << request.model_source
            << ") on " << options.device << " at " << options.rate_hz << " Hz for "
            << options.duration_s << " s" << (options.simulated_time ? " of simulated time" : "")
            << "\n";
  auto watcher = std::make_shared<ParameterFileWatcher>(options.watch_params);
  std::shared_ptr<KeypadTuning> keypad;
  if (options.keys) {
    if (options.simulated_time) throw UsageError("--keys needs real time (not --simulated-time)");
    if (model.kind() != ModelKind::kSensory) {
      throw UsageError("--keys tunes the sensory model's perceptual controls (--model sensory)");
    }
    keypad = std::make_shared<KeypadTuning>(model);
  }
  if (!options.watch_params.empty() || keypad) {
    request.control = [watcher, keypad](haptic::Playback& playback) {
      watcher->poll(playback);
      if (keypad) keypad->poll(playback);
      return true;
    };
  }
  std::shared_ptr<station::StationSession> station;
  if (options.station.station) {
    // The scene is read now: a bad scene file stops the run before the device moves.
    station = std::make_shared<station::StationSession>(options.station.request());
    request.on_start = [station](haptic::Playback& playback) {
      station->open(playback.loop().snapshot());
    };
    request.on_end = [station] { station->close(); };
  }
  const haptic::PlaybackSummary summary = play_model(model, request);
  std::cout << summary.brief_report() << "\n";
  if (station) std::cout << station->brief_report() << "\n";
  if (!summary.stop_cause.empty()) {
    throw std::runtime_error("the playback stopped after " +
                             format_significant(summary.duration_s, 3) + " s of " +
                             format_number(options.duration_s) + " s (session " +
                             request.session_path.string() + " kept): " + summary.stop_cause);
  }
}

}  // namespace

void add_play_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<PlayOptions>();
  CLI::App* play = app.add_subcommand(
      "play", "Render a door model on a haptic device and record every tick as a session");
  add_model_options(*play, options->model);
  play->add_option("--device", options->device,
                   "sim (simulated HapticMaster with a virtual user), sim:rotary, or "
                   "hapticmaster://HOST[:PORT]")
      ->capture_default_str();
  play->add_option("--out", options->out, "The session to write (must not exist)")->required();
  play->add_option("--duration-s", options->duration_s, "How long to play")
      ->check(number_range(0.01, 86400.0))
      ->capture_default_str();
  play->add_option("--rate-hz", options->rate_hz, "Render loop rate (100 to 4000 Hz)")
      ->check(number_range(100.0, 4000.0))
      ->capture_default_str();
  play->add_flag("--simulated-time", options->simulated_time,
                 "Run a simulated device in simulated time, as fast as possible");
  play->add_flag("--no-fifo", options->no_fifo,
                 "Do not ask for SCHED_FIFO (the tick's thread and a HapticMaster's I/O thread)");
  play->add_option("--hand-cycle-s", options->hand_cycle_s,
                   "Simulated devices: the virtual user's open-close cycle")
      ->check(number_range(1.0, 600.0))
      ->capture_default_str();
  play->add_option("--pushes-hz", options->pushes_hz,
                   "Simulated devices: mean rate of the virtual user's pushes off the arc")
      ->check(number_range(0.0, 50.0))
      ->capture_default_str();
  play->add_option("--push-N", options->push_N, "Simulated devices: the pushes' amplitude")
      ->check(number_range(0.0, 200.0))
      ->capture_default_str();
  play->add_option("--seed", options->seed, "Simulated devices: noise and pushes")
      ->capture_default_str();
  play->add_option("--max-force-N", options->max_force_N,
                   "The safety layer's force limit (the device's own limit also applies; rotary "
                   "devices: N*m)")
      ->check(number_range(0.1, 1000.0))
      ->capture_default_str();
  play->add_option("--max-force-rate", options->max_force_rate_N_per_s,
                   "The safety layer's force-rate limit, N/s (rotary: N*m/s)")
      ->check(number_range(1.0, 1e6))
      ->capture_default_str();
  play->add_option("--max-tick-interval-ms", options->max_tick_interval_ms,
                   "A longer gap between two ticks is a late tick: counted in the summary, the "
                   "device holds the last force meanwhile and playback goes on")
      ->check(number_range(0.5, 1000.0))
      ->capture_default_str();
  play->add_option("--max-tick-stall-ms", options->max_tick_stall_ms,
                   "A longer gap between two ticks is a stall: the safety layer ramps the force "
                   "down and stops (the HapticMaster's I/O watchdog stops the device itself)")
      ->check(number_range(1.0, 1000.0))
      ->capture_default_str();
  play->add_flag("--keys", options->keys,
                 "Live tuning from the keypad (stdin must be a terminal): + - heavier/lighter, "
                 "u U unlatch, c C closing, s S smoothness, n N snap, r reset");
  play->add_option("--watch-params", options->watch_params,
                   "A parameter file to watch: whenever it changes (the viewer's tuning layout "
                   "saves it), its values are played from the next tick");
  add_station_options(*play, options->station);
  play->callback([options, &action] { action = [options] { run_play(*options); }; });
}

}  // namespace doorbench::app
