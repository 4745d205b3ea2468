#include "haptic/playback.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "core/clock.h"
#include "core/number_format.h"

namespace doorbench::haptic {

std::string PlaybackOptions::validate() const {
  if (std::string problem = loop.validate(); !problem.empty()) return problem;
  if (std::string problem = arc.validate(); !problem.empty()) return "arc: " + problem;
  if (std::string problem = real_time.validate(); !problem.empty()) return problem;
  if (!(duration_s > 0.0) || !std::isfinite(duration_s)) return "duration_s must be > 0";
  return "";
}

std::string PlaybackSummary::brief_report() const {
  std::ostringstream text;
  text.precision(4);
  text << ticks << " ticks over " << duration_s << " s into " << session_path.string()
       << "; max commanded force " << max_commanded_force << " " << force_unit;
  if (max_radial_error_m && max_axial_error_m) {
    text << ", arc error radial/axial max " << *max_radial_error_m * 1e3 << "/"
         << *max_axial_error_m * 1e3 << " mm";
  }
  text << "; " << parameter_changes << " parameter changes; " << clipped_ticks << " ticks clipped; "
       << records_dropped << " records dropped; safety " << to_string(final_state);
  if (!safety_events.empty()) {
    // Each kind once, in order of first appearance, with its count.
    text << " (events:";
    std::vector<std::string> kinds;
    for (const std::string& event : safety_events) {
      if (std::find(kinds.begin(), kinds.end(), event) == kinds.end()) kinds.push_back(event);
    }
    for (const std::string& kind : kinds) {
      const auto count = std::count(safety_events.begin(), safety_events.end(), kind);
      text << " " << kind;
      if (count > 1) text << " x" << count;
    }
    text << ")";
  }
  if (!stop_cause.empty()) text << "\nstopped early: " << stop_cause;
  if (constraint_on_device) text << "\narc constraint, end stops and damper: on the device";
  if (startup) {
    const auto ms = [](double s) { return format_significant(s * 1e3, 3) + " ms"; };
    text << "\nstart-up: the device's checks " << ms(startup->device_checks_s) << ", its start "
         << ms(startup->device_start_s) << "; from then, the first tick after "
         << ms(startup->first_tick_after_s) << " and its command on the device after "
         << (std::isnan(startup->first_command_after_s) ? std::string("(never)")
                                                        : ms(startup->first_command_after_s));
  }
  if (timing) text << "\ntiming: " << timing->brief_report();
  if (!warning.empty()) text << "\nwarning: " << warning;
  return text.str();
}

Playback::Playback(HapticDevice& device, const DoorModel& model, const PlaybackOptions& options,
                   const std::filesystem::path& session_path, const SessionMetadata& metadata,
                   const PlaybackSetup& setup)
    : device_(device), options_(options), current_model_(playable_model(model)) {
  if (std::string problem = options_.validate(); !problem.empty()) {
    throw std::invalid_argument("playback: " + problem);
  }
  mapping_ = std::make_unique<DoorMapping>(device_.limits().kinematics, options_.arc,
                                           model.geometry().handle_radius_m);
  auto first = std::make_unique<PlaybackParameters>(current_model_, *mapping_,
                                                    "start: " + setup.model_source);
  const std::string description = first->description;
  device_inertia_ = first->device_inertia;
  if (options_.stiff_parts_on_device) {
    options_.loop.constraint_on_device = device_.render_stiff_parts_on_device(
        *mapping_, -0.02, model.geometry().theta_max_rad + 0.02);
  }
  // Everything slow comes before the device's start: its checks (after which limits() is its
  // own), the loop with its record ring, the session file. start() then only enters the
  // force-controlled state, just before the first tick (start_device()), so that a busy
  // machine does not leave the device waiting for a loop that is not there yet.
  const double checks_began_s = monotonic_now_s();
  device_prepared_ = true;
  device_.prepare(device_inertia_);
  startup_.device_checks_s = monotonic_now_s() - checks_began_s;
  if (std::string problem =
          mapping_->check_workspace(device_.limits(), -0.02, model.geometry().theta_max_rad + 0.02,
                                    options_.loop.safety.workspace_margin_m);
      !problem.empty()) {
    throw std::invalid_argument("playback on " + device_.name() + ": " + problem);
  }
  loop_ = std::make_unique<RenderLoop>(device_, *mapping_, std::move(first), options_.loop);
  recorder_ = std::make_unique<TickRecorder>(session_path, metadata, *loop_, current_model_, setup);
  recorder_->note_parameter_set(loop_->mailbox().in_use(), description, current_model_);
}

void Playback::start_device() {
  const double start_began_s = monotonic_now_s();
  device_.start(device_inertia_);
  device_started_at_s_ = monotonic_now_s();
  startup_.device_start_s = device_started_at_s_ - start_began_s;
}

Playback::~Playback() {
  try {
    if (!finished_ && recorder_) recorder_->close();
  } catch (...) {
    // the recorder reports its own failure on stderr
  }
  if (device_prepared_) device_.stop();
}

std::string Playback::change_parameters(const DoorModel& model, const std::string& description) {
  DoorModel playable = playable_model(model);
  if (playable.kind() != current_model_.kind() ||
      playable.term_count() != current_model_.term_count()) {
    return "a live change keeps the model and its effects (only values change); play another "
           "model in a new run";
  }
  auto parameters = std::make_unique<PlaybackParameters>(playable, *mapping_, description);
  if (std::string problem = loop_->check(*parameters); !problem.empty()) {
    recorder_->add_event({.time_s = loop_->status().time_s,
                          .kind = "parameters_refused",
                          .channel = "",
                          .detail = std::string(description).append(": ").append(problem)});
    return problem;
  }
  // Noted under the id it will get before the tick can take it, so that the session names
  // the set from its first tick.
  recorder_->note_parameter_set(loop_->mailbox().next_id(), description, playable);
  if (std::string problem = loop_->publish(std::move(parameters)); !problem.empty()) {
    return problem;  // cannot happen: checked above
  }
  current_model_ = std::move(playable);
  return "";
}

PlaybackSummary Playback::run_simulated(const std::function<void(double)>& advance_device_to,
                                        const std::function<void(double)>& between_ticks) {
  if (finished_) throw std::logic_error("playback: already run");
  start_device();
  const double period = loop_->period_s();
  const auto tick_count = static_cast<std::uint64_t>(std::llround(options_.duration_s / period));
  // After the duration, the stop ramp: at most a second more.
  const std::uint64_t limit = tick_count + static_cast<std::uint64_t>(std::ceil(1.0 / period));
  for (std::uint64_t tick = 0; tick < limit; ++tick) {
    const double time_s = static_cast<double>(tick) * period;
    if (tick == tick_count) loop_->request_stop();
    advance_device_to(time_s);
    loop_->tick(time_s);
    if (between_ticks) between_ticks(time_s);
    if (loop_->records().size() > loop_->records().capacity() / 2) recorder_->drain();
    if (loop_->stopped()) break;
  }
  return finish(std::nullopt, "", false);
}

PlaybackSummary Playback::run_real_time(
    const std::function<bool(const RenderLoop::Status&)>& every_status, double status_interval_s) {
  if (finished_) throw std::logic_error("playback: already run");
  RealTimeOptions real_time = options_.real_time;
  real_time.duration_s = options_.duration_s;
  RealTimeRunner runner(*loop_, real_time);
  recorder_->start();
  start_device();
  runner.start();
  bool stopped_by_caller = false;
  while (!runner.finished()) {
    std::this_thread::sleep_for(std::chrono::duration<double>(status_interval_s));
    if (every_status && !every_status(loop_->status())) {
      stopped_by_caller = true;
      break;
    }
  }
  runner.stop();
  return finish(runner.report(), runner.warning(), stopped_by_caller);
}

std::string Playback::stop_cause() const {
  if (!recorder_->first_trip().empty()) return recorder_->first_trip();
  // No trip in the ticks: a fault the device met while stopping, if any.
  return device_.stop_reason();
}

PlaybackSummary Playback::finish(std::optional<TimingReport> timing, const std::string& warning,
                                 bool stopped_by_caller) {
  // The device first (zero force, its own stop state), then the file, which gets the reason.
  const double first_command_s = device_.first_command_arrival_s();
  device_.stop();
  device_prepared_ = false;
  recorder_->stop();
  recorder_->drain();
  PlaybackSummary summary;
  summary.stop_cause = stop_cause();
  recorder_->add_event({.time_s = loop_->status().time_s,
                        .kind = "stop",
                        .channel = "",
                        .detail = !summary.stop_cause.empty() ? summary.stop_cause
                                  : stopped_by_caller
                                      ? std::string("end: stopped by the operator")
                                      : std::string("end: the run's duration was played")});
  recorder_->close();
  finished_ = true;
  if (timing) {
    summary.startup = startup_;
    summary.startup->first_tick_after_s = timing->first_tick_s - device_started_at_s_;
    summary.startup->first_command_after_s = first_command_s - device_started_at_s_;
  }
  summary.session_path = recorder_->path();
  const RenderLoopCounters counters = loop_->counters();
  summary.ticks = counters.ticks;
  summary.constraint_on_device = options_.loop.constraint_on_device;
  summary.clipped_ticks = counters.clipped_ticks;
  summary.records_dropped = counters.records_dropped;
  summary.parameter_changes = counters.parameter_changes;
  summary.final_state = loop_->safety_state();
  summary.timing = std::move(timing);
  summary.warning = warning;
  // The figures come from the session as written: what was recorded is what is reported.
  const SessionReader session(summary.session_path);
  const ChannelSlice x = session.read("commanded_force_x");
  const ChannelSlice y = session.read("commanded_force_y");
  const ChannelSlice z = session.read("commanded_force_z");
  summary.force_unit = session.channel("commanded_force_x").unit;
  for (std::size_t i = 0; i < x.raw.size(); ++i) {
    summary.max_commanded_force =
        std::max(summary.max_commanded_force,
                 std::sqrt(x.raw[i] * x.raw[i] + y.raw[i] * y.raw[i] + z.raw[i] * z.raw[i]));
  }
  if (!x.time_s.empty()) summary.duration_s = x.time_s.back() - x.time_s.front();
  if (device_.limits().kinematics == Kinematics::kCartesian3) {
    double radial_m = 0.0, axial_m = 0.0;
    for (const double error : session.read("radial_error").raw) {
      radial_m = std::max(radial_m, std::abs(error));
    }
    for (const double error : session.read("axial_error").raw) {
      axial_m = std::max(axial_m, std::abs(error));
    }
    summary.max_radial_error_m = radial_m;
    summary.max_axial_error_m = axial_m;
  }
  for (const SessionEvent& event : session.events()) {
    if (event.kind == "safety")
      summary.safety_events.push_back(event.detail.substr(0, event.detail.find(':')));
  }
  return summary;
}

}  // namespace doorbench::haptic
