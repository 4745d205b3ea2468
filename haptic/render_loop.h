#pragma once
// The render loop's tick (docs/haptic.md): read the device, map the end-effector to the door
// (θ, ω), evaluate the door model and its effects, add the passivity controller's damping and
// the arc constraint, pass everything through the safety layer, command the force, and hand a
// record of the tick to the session recorder.
//
// The MuJoCo split: the constant part (options, mapping, device limits) is fixed at
// construction; the mutable part (the parameter set in use, the safety and passivity state,
// counters) changes tick by tick; tick() is the step function over both. tick() never
// allocates, locks, logs or does I/O (tests/haptic/test_render_loop.cpp counts allocations): its
// output goes through a preallocated single-producer ring (SpscRing) to whoever records it,
// and new parameter sets come in through the ParameterMailbox at tick boundaries; the door's
// angle and its events go out through a seqlock (DoorSnapshotChannel) to whoever shows them.
//
// Who renders the inertia: an admittance device (the HapticMaster, the simulated one)
// renders the door's inertia as its own mass, J / (r_h · r_arc) (DoorMapping); the host sends
// it with command_inertia() whenever a new parameter set changes it. A device without
// admittance (max_inertia 0) gets the inertia from the host: the tick adds −J_dev · a, with a
// the end-effector's acceleration estimated from the velocity (documented as the weaker
// choice: it amplifies noise).
//
// Thread safety: one thread calls tick() (the real-time runner, or a test/demo driving
// simulated time); the mailbox and the ring are the only things other threads touch.
#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "acquisition/record/ring_buffer.h"
#include "analysis/model/door_model.h"
#include "haptic/device.h"
#include "haptic/door_mapping.h"
#include "haptic/door_snapshot.h"
#include "haptic/parameter_mailbox.h"
#include "haptic/safety.h"

namespace doorbench::haptic {

struct RenderLoopOptions {
  double rate_hz = 1000.0;  // 100 ... 4000
  SafetyOptions safety;
  PassivityOptions passivity;
  std::size_t record_ring_ticks = 65536;  // tick records buffered for the recorder (65 s at 1 kHz)
  // The device holds the end-effector on the arc with its own elements
  // (HapticDevice::render_stiff_parts_on_device): the tick sends only the door's torque.
  bool constraint_on_device = false;
  std::string validate() const;  // empty when usable, else one line naming the option
};

// Everything one tick did, for the session.
struct TickRecord {
  double time_s = 0.0;
  Vec3 position = Vec3::Zero();
  Vec3 velocity = Vec3::Zero();
  Vec3 measured_force = Vec3::Zero();
  Vec3 commanded_force = Vec3::Zero();
  double theta_rad = 0.0;
  double omega_rad_s = 0.0;
  double user_force_N = 0.0;         // along the arc
  double model_torque_Nm = 0.0;      // τ_m
  double passivity_torque_Nm = 0.0;  // the passivity controller's damping
  double radial_error_m = 0.0;
  double axial_error_m = 0.0;
  double safety_scale = 0.0;
  int parameter_set = 0;
  int term_count = 0;
  std::array<double, DoorModel::kMaxTerms> terms_Nm{};
  std::uint32_t events = 0;  // SafetyEvent bits that began this tick
  bool clipped = false;
  std::uint64_t device_sequence = 0;
};

struct RenderLoopCounters {
  std::uint64_t ticks = 0;
  std::uint64_t records_dropped = 0;  // the recorder fell behind and the ring was full
  std::uint64_t parameter_changes = 0;
  std::uint64_t clipped_ticks = 0;
};

class RenderLoop {
 public:
  // `device` and `mapping` must outlive the loop. The device must have been started. The
  // initial set is checked (check_parameter_set); throws std::invalid_argument with the reason.
  RenderLoop(HapticDevice& device, const DoorMapping& mapping,
             std::unique_ptr<PlaybackParameters> initial, const RenderLoopOptions& options);

  const RenderLoopOptions& options() const { return options_; }
  double period_s() const { return 1.0 / options_.rate_hz; }
  const DoorMapping& mapping() const { return mapping_; }
  DeviceLimits device_limits() const { return limits_; }
  // For the recorder's descriptions of events (any thread: SafetyLayer::describe() and
  // HapticDevice::stop_reason() are not the tick's calls).
  const SafetyLayer& safety() const { return safety_; }
  const HapticDevice& device() const { return device_; }

  // Control side: checks a new set against the device and the loop period and publishes it;
  // returns "" and the id through `id`, or the reason it was refused (nothing published).
  std::string publish(std::unique_ptr<PlaybackParameters> parameters, int* id = nullptr);
  // The check publish() makes: "" when the set may be played, else the reason.
  std::string check(const PlaybackParameters& parameters) const;
  ParameterMailbox& mailbox() { return mailbox_; }

  // The step: one tick at `time_s` (the loop's clock). Real-time safe.
  void tick(double time_s) noexcept;
  // Asks the safety layer to ramp down and stop (takes effect at the next tick).
  void request_stop() noexcept { stop_requested_.store(true, std::memory_order_release); }
  SafetyState safety_state() const noexcept {
    return safety_state_.load(std::memory_order_acquire);
  }
  bool stopped() const noexcept { return safety_state() == SafetyState::kStopped; }

  // The consumer end of the records (one consumer thread).
  SpscRing<TickRecord>& records() { return records_; }
  // Snapshot for status lines; read from any thread (relaxed: figures, not synchronization).
  RenderLoopCounters counters() const noexcept;
  // The newest tick's state for status lines (any thread; may tear between fields).
  struct Status {
    double time_s, theta_rad, omega_rad_s, user_force_N;
    double commanded_force_N;  // the command along the arc (a rotary device: its torque, N*m)
    int parameter_set;
  };
  Status status() const noexcept;
  // The newest tick's door state and its event counters, consistent across fields (any
  // thread; the station draws and sounds the door from it). The event angles come from the
  // first parameter set's model.
  const DoorSnapshotChannel& snapshot() const noexcept { return snapshot_; }

 private:
  HapticDevice& device_;
  const DoorMapping& mapping_;
  RenderLoopOptions options_;
  DeviceLimits limits_;
  SafetyLayer safety_;
  PassivityController passivity_;
  ParameterMailbox mailbox_;
  SpscRing<TickRecord> records_;
  const PlaybackParameters* parameters_ = nullptr;
  double commanded_inertia_ = 0.0;
  bool host_renders_inertia_ = false;
  bool have_previous_ = false;
  double previous_time_s_ = 0.0;
  Vec3 previous_velocity_ = Vec3::Zero();
  std::array<double, DoorModel::kMaxTerms> terms_{};
  std::atomic<bool> stop_requested_{false};
  bool stop_forwarded_ = false;
  bool braked_ = false;  // device_.brake() called (velocity or workspace trip, or stopped)
  std::atomic<SafetyState> safety_state_{SafetyState::kStarting};
  std::atomic<std::uint64_t> ticks_{0}, dropped_{0}, changes_{0}, clipped_{0};
  std::atomic<double> status_time_s_{0.0}, status_theta_{0.0}, status_omega_{0.0},
      status_user_force_{0.0}, status_command_{0.0};
  std::atomic<int> status_set_{0};
  DoorSnapshotChannel snapshot_;
};

}  // namespace doorbench::haptic
