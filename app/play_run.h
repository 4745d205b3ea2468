#pragma once
// One playback run from the command line's point of view: open the device, play a model on
// it into a session, show status, report. Shared by `doorbench play`, `doorbench ab` and the
// demo.
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "acquisition/rig/rig_file.h"
#include "analysis/model/door_model.h"
#include "haptic/device_factory.h"
#include "haptic/playback.h"
#include "study/presenter.h"

namespace doorbench::app {

struct PlayRequest {
  haptic::DeviceRequest device;
  haptic::PlaybackOptions playback;
  std::filesystem::path session_path;
  std::string model_source;  // for the session: the --params path or "reference door"
  std::string effects;       // as given
  std::string operator_name = "doorbench play";
  std::string product_id = "virtual door";
  std::string notes;  // put before the model's source in the session's notes
  // The safety layer's velocity trip in the device's units; unset: its default (1 m/s) for a
  // Cartesian device, 6 rad/s (twice a brisk slam) for a rotary one.
  std::optional<double> velocity_trip;
  bool show_status = true;  // a status line on stderr while playing in real time
  // Live tuning: called about every 0.1 s (real time) on the control thread; it may call
  // playback.change_parameters(). Returning false ends the run early.
  std::function<bool(haptic::Playback&)> control;
  // Called once the playback exists, before its first tick (the station opens on its
  // snapshot), and `on_end` once the run is over, before the playback goes, on every path.
  std::function<void(haptic::Playback&)> on_start;
  std::function<void()> on_end;
};

// The session is written through a temporary file beside it and renamed into place when
// complete (acquisition/session/output_file.h), so a failure leaves no file under its name. Throws
// OutputRefused when it exists, std::runtime_error (device, session: naming the session's
// path) or std::invalid_argument (options, model).
haptic::PlaybackSummary play_model(const DoorModel& model, const PlayRequest& request);

// The device and the bench of the people-testing verbs' presenter (study/presenter.h):
// play_model with the presenter's settings (no status line), and the rig's recorder.
study::PlayOnDevice presentation_player();
study::RecordRealDoor real_door_recorder(std::shared_ptr<const RigDefinition> rig);

}  // namespace doorbench::app
