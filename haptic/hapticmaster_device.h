#pragma once
// The MOOG FCS HapticMaster over its TCP text protocol (haptic/hapticmaster_protocol.h;
// docs/hapticmaster.md). The render loop's tick never touches the socket: an I/O thread
// owns it, sends the newest commanded force (a bias force object on the device) with
// "get measpos;get modelvel;get measforce" in one round trip per period, and publishes each
// reply as a DeviceSample through a lock-free triple buffer that read() takes.
//
// Fail-safe (docs/haptic-safety.md, "the HapticMaster's fail-safe"): a bias force stays on the
// device until a new one is sent, so no failure may end with the link merely closed. On every
// failure of a round trip (error reply, corrupt or closed stream, no reply), on brake(), when
// the tick stops publishing commands for command_watchdog_s, and in stop(), the driver sends
// zero force and "set state stop" in one request: on the open connection while its stream is
// intact, else on a fresh connection, each attempt within emergency_timeout_s. Only then is
// the link reported lost.
//
// Start-up follows the device's own checks: the state, both emergency signals, the position
// calibration (homing by "set state init" when needed), "remove all", the workspace read from
// the device, the inertia set and read back (start(); startup_report()).
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "haptic/device.h"

namespace doorbench::haptic {
namespace hm {
class Connection;
}

struct HapticMasterOptions {
  double connect_timeout_s = 2.0;  // TCP connect
  double reply_timeout_s = 0.5;    // one round trip; longer = link lost
  double io_rate_hz = 1000.0;      // round trips per second (at most; the link may be slower)
  // The I/O thread asks for SCHED_FIFO at this priority (1..99; 0: best effort), one below the
  // tick's (RealTimeOptions::fifo_priority): it is half of the haptic loop, and on a busy
  // machine a best-effort I/O thread delays every round trip. When not permitted it runs best
  // effort (io_thread_fifo() says which).
  int io_fifo_priority = 79;
  // The name of the bias force object the driver creates on the device.
  std::string bias_object = "doorbench_bias";
  // One round trip's commands as one ';'-joined message (true), or as one message each,
  // sent together (false): the fallback if a device answers a joined message with a single
  // reply instead of one per command (docs/hapticmaster.md, assumptions).
  bool join_commands = true;
  // The fail-safe: each attempt to send zero force and "set state stop" (on the open
  // connection, then on a fresh one) gives up after this long.
  double emergency_timeout_s = 0.1;
  // The I/O thread's watchdog on the tick: no new command for this long and it zeroes the
  // force and stops the device itself. The safety layer's max_tick_stall_s (the same default
  // and derivation, docs/haptic-safety.md). 0 turns it off (tests that command by hand). It
  // arms at the render loop's first command (the first command_force() or command_inertia()
  // after start()): what lies between start() and the first tick (the session file, the
  // recorder, the threads' start) may take longer on a busy machine, and the device holds
  // zero force meanwhile.
  double command_watchdog_s = 0.1;
  // The first command must come within this long of start(), or the I/O thread stops the
  // device itself (a host that hangs before its first tick leaves nothing running).
  double first_command_timeout_s = 5.0;
  // Homing ("set state init") when the device reports its position uncalibrated: how long to
  // wait for it to end, and who hears about its progress (one line every second or so).
  double homing_timeout_s = 60.0;
  std::function<void(const std::string&)> progress;
  // Stiff parts on the device (render_stiff_parts_on_device): the arc constraint's springs
  // take the ArcGeometry's stiffness and damping; these are the rest (docs/hapticmaster.md).
  double device_damping_N_s_per_m = 5.0;      // the permanent damper, each axis
  double end_stop_stiffness_N_per_m = 10000;  // the walls at the ends of the door's range
  double end_stop_damping_ratio = 0.7;        // their dampfactor (fraction of critical)
  double element_max_force_N = 60.0;          // each element's maxforce
  std::string validate() const;               // "" or one line naming the option
};

// What start() found and did, for the bring-up check and the session's notes.
struct HapticMasterStartup {
  std::string initial_state;               // the reply to "get state", without quotes
  bool emergency_button = false;           // "get emergencybuttonpushed": true = pushed
  bool emergency_relay_closed = true;      // "get emergencyrelay": false = not started
  bool emergency_signals_reported = true;  // false: the device answered them with errors
  bool was_calibrated = true;              // "get position_calibrated" before homing
  double homing_s = 0.0;                   // how long homing took (0 when not needed)
  std::string workspace_source;            // "device" (read back) or why the assumed box is used
  double base_axis_offset_m = 0.0;         // the base axis behind the origin (workspace_r's middle)
  Vec3 workspace_r_phi_z_min = Vec3::Zero();  // as read: r (m), φ (rad), z (m)
  Vec3 workspace_r_phi_z_max = Vec3::Zero();
  double inertia_read_back_kg = 0.0;  // "get inertia" after "set inertia"
};

// A single-producer single-consumer triple buffer: the writer fills back() and publishes
// it, the reader takes the newest published value; neither ever waits, locks or allocates.
template <class T>
class TripleBuffer {
 public:
  T& back() { return slots_[back_]; }
  void publish() {
    back_ = static_cast<std::uint8_t>(middle_.exchange(back_ | kFresh, std::memory_order_acq_rel) &
                                      kIndex);
  }
  // Takes the newest published value if there is one; returns whether it did.
  bool update() {
    if ((middle_.load(std::memory_order_relaxed) & kFresh) == 0) return false;
    front_ =
        static_cast<std::uint8_t>(middle_.exchange(front_, std::memory_order_acq_rel) & kIndex);
    return true;
  }
  const T& front() const { return slots_[front_]; }

 private:
  static constexpr std::uint8_t kIndex = 3;
  static constexpr std::uint8_t kFresh = 4;
  T slots_[3]{};
  std::atomic<std::uint8_t> middle_{1};
  std::uint8_t back_ = 0;   // the writer's
  std::uint8_t front_ = 2;  // the reader's
};

class HapticMasterDevice : public HapticDevice {
 public:
  static constexpr std::size_t kRoundTripLog = 65536;
  // `address` is "host[:port]" (port 7654 by default). Throws DeviceError for a bad
  // address or options; does not connect (start() does).
  explicit HapticMasterDevice(const std::string& address, HapticMasterOptions options = {});
  ~HapticMasterDevice() override;
  HapticMasterDevice(const HapticMasterDevice&) = delete;
  HapticMasterDevice& operator=(const HapticMasterDevice&) = delete;

  std::string name() const override;  // "hapticmaster://host:port"
  // The assumed figures until start() has read the workspace from the device; then its box.
  DeviceLimits limits() const override;
  // The checks and the set-up (prepare) and the force state (start), as HapticDevice says.
  // prepare() connects, checks the state and both emergency signals, homes an uncalibrated
  // device, removes other programs' effects, reads the workspace (limits() is the device's
  // from then on), sets the inertia and reads it back, and creates the bias force object and
  // the stiff parts' elements; start() sets state force, takes the first reading and starts
  // the I/O thread (prepare() first when it was not called). Each throws DeviceError naming the
  // step: a pushed emergency button or an open emergency relay ("... emergency button is
  // pushed: release it ..."), homing that does not end, an inertia the device does not take,
  // an error reply. On failure the device is left stopped.
  void prepare(double inertia) override;
  void start(double inertia) override;
  void stop() noexcept override;
  const HapticMasterStartup& startup_report() const { return startup_; }

  DeviceSample read() noexcept override;
  void command_force(const Vec3& force) noexcept override;
  void command_inertia(double inertia) noexcept override;
  void brake() noexcept override;
  // Creates, at start(), springs "doorbench_axial" (along the hinge axis, through the arc's
  // plane) and "doorbench_radial" (along the radius at the door's angle, moved by the I/O
  // thread as the door turns), end stops "doorbench_stop_closed"/"doorbench_stop_open" (one-
  // sided walls: springs with a deadband) and the damper "doorbench_damper". Always true.
  bool render_stiff_parts_on_device(const DoorMapping& mapping, double theta_min_rad,
                                    double theta_max_rad) override;

  // Round-trip times of the I/O thread's exchanges (s), newest last, up to the last 65536;
  // set-up thread only, once the I/O thread has ended (stop()) or for a snapshot.
  std::vector<double> round_trip_times_s() const;
  // True when the last failure or stop left the device at zero force in state "stop"
  // (confirmed by its replies); false when the emergency stop could not reach it.
  bool device_stopped() const { return device_stopped_.load(); }
  // Set-up-thread helper for the bring-up check: one command on the open connection, its
  // reply text (throws DeviceError on an error reply or a broken link). Not while the I/O
  // thread runs.
  std::string exchange(const std::string& command);
  // The bring-up check's disconnect test only: ends the I/O thread and closes the socket as
  // a crashed host would, sending nothing (no fail-safe). The device is then in whatever
  // state a crash would leave it; the caller must stop it on a new connection.
  void abandon_connection_for_test() noexcept;
  // Opens a connection without the start-up (for exchange() only; the check reads back what
  // a device kept after a disconnect). stop() then stops the device as usual.
  void connect_only();

  // Why the link was lost (first reason, prefixed with name()), or "" while it is fine.
  // Any thread but the tick's.
  std::string last_error() const;
  std::string stop_reason() const override { return last_error(); }
  double first_command_arrival_s() const noexcept override {
    return first_command_arrival_s_.load(std::memory_order_acquire);
  }
  // Round trips done by the I/O thread since start().
  std::uint64_t round_trips() const { return round_trips_.load(std::memory_order_relaxed); }
  // Whether the I/O thread got SCHED_FIFO at start() (set-up thread).
  bool io_thread_fifo() const { return io_thread_fifo_; }

 private:
  struct Command {
    Vec3 force = Vec3::Zero();
    double inertia = 0.0;
    std::uint64_t serial = 0;  // 0: start()'s own zero force; the tick's commands count from 1
  };

  // Runs on the I/O thread; its arguments are what start() sent and published.
  void io_loop(double sent_inertia, DeviceSample sample);
  // The watchdog's reason to stop the device now, or "": before the first command (`armed`
  // false) the first-command limit from `started_s`, after it command_watchdog_s from
  // `last_command_s` (monotonic_now_s() seconds). I/O thread.
  std::string watchdog_verdict(bool armed, double started_s, double last_command_s) const;
  void fail(const std::string& reason);
  // The fail-safe: zero force and "set state stop" in one request, on the open connection if
  // `connection_intact`, else (or if that fails) on a fresh one. Returns "" or why it could
  // not reach the device. Sets device_stopped_. Any thread that owns the connection.
  std::string emergency_stop(bool connection_intact) noexcept;
  // Fails with `reason`, runs the fail-safe, then publishes the lost link (I/O thread).
  void lose_link(const std::string& reason, bool connection_intact, DeviceSample sample) noexcept;
  // Zero force, "set state stop", remove the bias object, in one request; the fail-safe if
  // that does not go through.
  void send_shutdown() noexcept;
  // One command's round trip in the set-up phase: its replies; throws DeviceError naming the
  // command when the link fails (then the connection is no longer intact).
  std::vector<std::string> round_trip_one(const std::string& command);
  // The same, and throws DeviceError with the reply's text on an error reply.
  std::string expect_ok(const std::string& command);
  // start()'s stages, in order.
  void identify();
  void check_emergency_signals();
  void ensure_calibrated();
  void clear_effects();
  void read_workspace();
  void set_inertia_checked(double inertia);
  void create_bias_and_elements();
  // Runs set-up steps; on any exception leaves the device as stop() would and rethrows.
  void guarded(const std::function<void()>& steps);
  void create_device_elements();
  // The commands that put the radial spring at the door's angle θ.
  std::vector<std::string> radial_spring_at(double theta_rad) const;
  DeviceSample first_reading();

  std::string host_;
  int port_ = 0;
  HapticMasterOptions options_;
  std::unique_ptr<hm::Connection> connection_;
  std::thread io_thread_;
  std::atomic<bool> stop_requested_{false};
  std::atomic<bool> brake_requested_{false};
  std::atomic<bool> link_ok_{false};
  std::atomic<bool> device_stopped_{false};
  bool connection_intact_ = false;  // the open connection's stream is in step (owner thread)
  bool bias_created_ = false;
  const DoorMapping* arc_ = nullptr;  // set: stiff parts on the device
  double stop_theta_min_rad_ = 0.0, stop_theta_max_rad_ = 0.0;
  bool elements_created_ = false;
  bool io_thread_fifo_ = false;
  double prepared_inertia_ = kNaN;  // the inertia prepare() set, until start() consumes it
  HapticMasterStartup startup_;
  DeviceLimits limits_;
  std::vector<double> round_trip_times_s_;  // ring of the last kRoundTripLog (I/O thread)
  std::size_t round_trip_next_ = 0;
  std::atomic<std::uint64_t> round_trips_{0};
  std::atomic<double> first_command_arrival_s_{kNaN};

  TripleBuffer<DeviceSample> samples_;  // I/O thread -> tick
  TripleBuffer<Command> commands_;      // tick -> I/O thread
  Command staged_;                      // the tick's copy of what it last commanded
  DeviceSample last_read_;              // the tick's newest sample

  mutable std::mutex error_mutex_;  // only the I/O thread and last_error(), never the tick
  std::string last_error_;
};

}  // namespace doorbench::haptic
