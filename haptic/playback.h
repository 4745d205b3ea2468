#pragma once
// One playback run: a door model rendered on a device by the render loop, every tick
// recorded into a session. What `doorbench play`, the A/B trials and the demo share.
//
// Two ways to run:
//  - real time (run_real_time): the RealTimeRunner's thread ticks at the loop's rate on the
//    device's real clock, a writer thread streams the ticks into the session, and the calling
//    thread shows status and takes live parameter changes;
//  - simulated time (run_simulated, simulated devices only): one thread advances the device's
//    simulated clock by one period, ticks, and drains the records, as fast as it can. Used by
//    tests, the demo and benchmarks: the same tick, deterministic, independent of load.
//
// Thread safety: a Playback is driven by one control thread; change_parameters() may be called
// from that thread while run_real_time() is in its status callback.
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "haptic/realtime_runner.h"
#include "haptic/render_loop.h"
#include "haptic/tick_recorder.h"

namespace doorbench::haptic {

struct PlaybackOptions {
  RenderLoopOptions loop;
  ArcGeometry arc;
  RealTimeOptions real_time;
  double duration_s = 10.0;  // > 0
  // Ask the device to render the arc constraint, the ends of the door's range and a damper
  // with its own elements (HapticDevice::render_stiff_parts_on_device); a device that cannot
  // (the simulated ones) gets them from the host as before.
  bool stiff_parts_on_device = true;
  std::string validate() const;
};

// How long a real-time run took to begin.
struct StartupTiming {
  double device_checks_s = kNaN;  // HapticDevice::prepare(): connect, checks, homing
  double device_start_s = kNaN;   // HapticDevice::start(): into the force-controlled state
  // From the end of start() (the device in its force state, zero force) to the render loop's
  // first tick, and to that tick's command taking effect on the device (NaN: it never did).
  double first_tick_after_s = kNaN;
  double first_command_after_s = kNaN;
};

struct PlaybackSummary {
  std::filesystem::path session_path;
  std::uint64_t ticks = 0;
  double duration_s = 0.0;
  double max_commanded_force = 0.0;  // in force_unit
  std::string force_unit = "N";      // the device's (device_units): N, or N*m for a rotary one
  // The handle's largest distance off the door's arc, radially and along the hinge; none for a
  // rotary device, whose shaft is the hinge and has no arc to leave.
  std::optional<double> max_radial_error_m, max_axial_error_m;
  std::uint64_t clipped_ticks = 0, records_dropped = 0, parameter_changes = 0;
  SafetyState final_state = SafetyState::kStarting;
  std::vector<std::string> safety_events;  // names, in order, e.g. "start_ramp_done"
  // Why the run ended before it was asked to: the first trip with its figure, a lost link with
  // the device's own text ("link_lost: hapticmaster://...: watchdog: the render loop sent no
  // command for 0.13 s (limit 0.1 s); the device was stopped (zero force, state stop)"), or a
  // stop that did not reach the device. "" when it ended as asked (its duration played, or the
  // caller stopped it). The session's "stop" event says the same.
  std::string stop_cause;
  std::optional<TimingReport> timing;    // real time only
  std::optional<StartupTiming> startup;  // real time only
  std::string warning;                   // e.g. no SCHED_FIFO
  bool constraint_on_device = false;     // the device held the arc with its own elements
  std::string brief_report() const;
};

class Playback {
 public:
  // Prepares the device with the model's inertia (its checks: HapticDevice::prepare), builds
  // the loop and creates the session; the run_*() calls start the device just before the first
  // tick. Throws DeviceError (the device), std::invalid_argument (options, an unplayable model,
  // a door outside the device's workspace: the message says why) or SessionError (the file).
  Playback(HapticDevice& device, const DoorModel& model, const PlaybackOptions& options,
           const std::filesystem::path& session_path, const SessionMetadata& metadata,
           const PlaybackSetup& setup);
  ~Playback();

  const DoorMapping& mapping() const { return *mapping_; }
  RenderLoop& loop() { return *loop_; }
  TickRecorder& recorder() { return *recorder_; }
  const DoorModel& current_model() const { return current_model_; }

  // Control side: a new parameter set, checked, recorded and handed to the tick at its next
  // boundary. Returns "" or the reason it was refused (then nothing changes).
  std::string change_parameters(const DoorModel& model, const std::string& description);

  // Simulated time: before each tick `advance_device_to(t)` brings the simulated device to the
  // tick's time; `between_ticks(t)` (optional) runs on the same thread after each tick, e.g. to
  // change parameters at a scripted time. Ends after duration_s (then the safety layer's
  // stop ramp) or when the safety layer stops.
  PlaybackSummary run_simulated(const std::function<void(double)>& advance_device_to,
                                const std::function<void(double)>& between_ticks = {});
  // Real time: `every_status(status)` is called about every status_interval_s on this thread;
  // returning false stops the run (the safety ramp-down, then the end).
  PlaybackSummary run_real_time(const std::function<bool(const RenderLoop::Status&)>& every_status,
                                double status_interval_s = 0.1);

 private:
  PlaybackSummary finish(std::optional<TimingReport> timing, const std::string& warning,
                         bool stopped_by_caller);
  // Why the run ended (PlaybackSummary::stop_cause), after the device's stop().
  std::string stop_cause() const;
  // The device's start() (its force state), timed.
  void start_device();

  HapticDevice& device_;
  PlaybackOptions options_;
  std::unique_ptr<DoorMapping> mapping_;
  std::unique_ptr<RenderLoop> loop_;
  std::unique_ptr<TickRecorder> recorder_;
  DoorModel current_model_;
  bool device_prepared_ = false;       // prepare() was called: stop() is owed
  double device_inertia_ = 0.0;        // what the first parameter set renders on the device
  StartupTiming startup_;              // the checks' and the start's times
  double device_started_at_s_ = kNaN;  // monotonic_now_s() when start() returned
  bool finished_ = false;
  // Tracked by the recorder's side from the records it drains.
  double max_force_ = 0.0, max_radial_ = 0.0, max_axial_ = 0.0;
};

}  // namespace doorbench::haptic
