#include "app/play_run.h"

#include <signal.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <system_error>

#include "acquisition/session/output_file.h"
#include "acquisition/session/session_file.h"
#include "app/session_recording.h"
#include "app/stop_signals.h"
#include "core/time_text.h"
#include "core/units.h"

namespace doorbench::app {
namespace {

haptic::PlaybackSummary play_into(const DoorModel& model, const PlayRequest& request,
                                  const std::filesystem::path& session_path) {
  haptic::OpenedDevice opened =
      haptic::open_device(request.device, request.playback.arc, model.geometry().handle_radius_m);
  if (request.device.simulated_time && !opened.simulated) {
    throw std::invalid_argument("--simulated-time needs a simulated device (got --device " +
                                request.device.uri + ")");
  }
  haptic::PlaybackOptions options = request.playback;
  if (request.velocity_trip) {
    options.loop.safety.velocity_trip = *request.velocity_trip;
  } else if (opened.device->limits().kinematics == haptic::Kinematics::kRotary1) {
    options.loop.safety.velocity_trip = 6.0;
  }
  SessionMetadata metadata;
  metadata.rig_name = "haptic playback on " + opened.device->name();
  metadata.operator_name = request.operator_name;
  metadata.product_id = request.product_id;
  metadata.start_time_utc = utc_now_iso8601();
  metadata.software_version = std::string("doorbench ") + DOORBENCH_VERSION;
  metadata.notes = (request.notes.empty() ? "" : request.notes + "; ") +
                   "model: " + request.model_source +
                   (request.effects.empty() ? "" : ", effects: " + request.effects);
  // In real time, Ctrl-C and SIGTERM are caught from before the device starts: one during
  // the start-up (homing may take a while) ends the run as soon as it begins; a second one
  // ends doorbench at once (app/stop_signals.h).
  std::optional<StopSignals> signals;
  if (!request.device.simulated_time) signals.emplace();
  haptic::Playback playback(
      *opened.device, model, options, session_path, metadata,
      haptic::PlaybackSetup{opened.device->name(), request.model_source, request.effects});
  // on_end before the playback is destroyed, whatever the way out.
  struct EndCall {
    const std::function<void()>& call;
    ~EndCall() {
      if (call) call();
    }
  } end_call{request.on_end};
  if (request.on_start) request.on_start(playback);
  if (request.device.simulated_time) {
    haptic::SimulatedDevice* device = opened.simulated;
    int ticks = 0;
    return playback.run_simulated([device](double t) { device->advance_to(t); },
                                  [&](double) {
                                    if (request.control && ++ticks % 100 == 0) {
                                      request.control(playback);
                                    }
                                  });
  }
  const bool tty = isatty(STDERR_FILENO) != 0;
  const char* command_unit = haptic::device_units(playback.loop().mapping().kinematics()).force;
  int calls = 0;
  bool signal_reported = false;
  haptic::PlaybackSummary summary =
      playback.run_real_time([&](const haptic::RenderLoop::Status& status) {
        if (const int signal_number = signals->received(); signal_number != 0) {
          if (!signal_reported) {
            std::fprintf(stderr, "%s%s: ramping the force down and stopping the device\n",
                         tty ? "\n" : "", signal_number == SIGINT ? "Ctrl-C" : "SIGTERM");
            signal_reported = true;
          }
          return false;
        }
        ++calls;
        if (request.show_status && (tty || calls % 10 == 0)) {
          const haptic::RenderLoopCounters counters = playback.loop().counters();
          const double rate_hz = status.time_s > 0 ? counters.ticks / status.time_s : 0.0;
          std::fprintf(stderr,
                       "%s%6.1f s  %7.1f Hz  θ %6.1f°  ω %6.1f°/s  hand %6.1f N  command %6.1f "
                       "%s  set %d  safety %s%s",
                       tty ? "\r" : "", status.time_s, rate_hz, status.theta_rad * kDegPerRad,
                       status.omega_rad_s * kDegPerRad, status.user_force_N,
                       status.commanded_force_N, command_unit, status.parameter_set,
                       std::string(haptic::to_string(playback.loop().safety_state())).c_str(),
                       tty ? "   " : "\n");
        }
        return request.control ? request.control(playback) : true;
      });
  if (request.show_status && tty) std::fprintf(stderr, "\n");
  return summary;
}

}  // namespace

haptic::PlaybackSummary play_model(const DoorModel& model, const PlayRequest& request) {
  if (std::filesystem::exists(request.session_path)) {
    throw OutputRefused(request.session_path.string() +
                        ": exists (sessions are never overwritten)");
  }
  // Whole or not at all (acquisition/session/output_file.h): a failed or full-disk playback leaves
  // no file under the session's name to block the next one.
  const std::filesystem::path partial = partial_path_for(request.session_path);
  haptic::PlaybackSummary summary;
  try {
    summary = play_into(model, request, partial);
  } catch (const SessionError& error) {
    std::error_code ignored;
    std::filesystem::remove(partial, ignored);
    throw SessionError(request.session_path.string() + ": cannot write: " + error.what());
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove(partial, ignored);
    throw;
  }
  commit_partial_file(partial, request.session_path);
  summary.session_path = request.session_path;
  return summary;
}

study::PlayOnDevice presentation_player() {
  return [](const DoorModel& model, const study::PlaySettings& settings) {
    PlayRequest play;
    play.device.uri = settings.device;
    play.device.simulated_time = settings.simulated_time;
    play.device.hand.duration_s = settings.hand_cycle_s;
    play.device.seed = settings.seed;
    play.playback.duration_s = settings.duration_s;
    play.session_path = settings.session_path;
    play.model_source = settings.model_source;
    play.operator_name = settings.operator_name;
    play.notes = settings.notes;
    play.show_status = false;
    play.control = settings.control;
    if (settings.on_start) {
      play.on_start = [&settings](haptic::Playback& playback) {
        settings.on_start(playback.loop().snapshot());
      };
    }
    play.on_end = settings.on_end;
    return play_model(model, play);
  };
}

study::RecordRealDoor real_door_recorder(std::shared_ptr<const RigDefinition> rig) {
  if (!rig) return {};
  return [rig](const study::RealDoorSettings& settings) {
    SessionRecordingOptions recording;
    recording.duration_s = settings.duration_s;
    recording.show_progress = false;
    recording.operator_name = settings.operator_name;
    recording.notes = settings.notes;
    record_rig_session(*rig, recording, settings.session_path);
  };
}

}  // namespace doorbench::app
