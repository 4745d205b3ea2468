#pragma once
// The safety layer, always on (docs/haptic-safety.md): it stands between the model and the
// device and is the last thing the tick does before command_force().
//
//  - force limit (magnitude of the commanded vector) and force-rate limit, each the smaller of
//    the device's and the options';
//  - a start-up ramp: the force is scaled from 0 to 1 over startup_ramp_s;
//  - late ticks degrade: a gap since the previous tick above max_tick_interval_s is a late
//    tick, counted (kEventLateTick) and played on, the force change after it still limited
//    as if the gap were max_tick_interval_s (the device held the last force meanwhile);
//  - trips: velocity above velocity_trip, position outside the workspace less its margin, a
//    stalled tick (time since the previous tick above max_tick_stall_s), a stalled
//    device (sample sequence unchanged for max_stale_ticks ticks), a lost link, a NaN or
//    infinite reading or desired force. A trip (or request_stop) takes the force of the last
//    tick and scales it linearly to zero over shutdown_ramp_s, then holds zero (state
//    kStopped); nothing restarts the layer but a new SafetyLayer (a new run);
//  - the passivity observer and controller (PassivityController below) on the model's active
//    terms (the snap zone's negative damping injects energy);
//  - parameter sets are checked before they reach the tick (check_parameter_set).
// Whatever the inputs (NaN, infinities, huge values), the force it returns is finite and its
// magnitude never exceeds the force limit, and between two ticks it never changes by more
// than the rate limit times the tick interval (except to go to zero at once when the tick's
// time itself is NaN or infinite: without a clock there is no ramp).
//
// Each step reports the events that began in that tick as bits, so that the tick can record
// them without building text; event_name() gives their names for the session.
//
// Thread safety: one SafetyLayer per render loop, used by its tick only. Its step is
// noexcept and never allocates.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "analysis/model/door_model.h"
#include "haptic/device.h"
#include "haptic/door_mapping.h"

namespace doorbench::haptic {

struct SafetyOptions {
  double max_force = 60.0;            // N (rotary: N*m); the device's own limit also applies
  double max_force_rate = 5000.0;     // N/s (rotary: N*m/s)
  double velocity_trip = 1.0;         // m/s (rotary: rad/s)
  double workspace_margin_m = 0.005;  // trip this far inside the device's workspace box
  double startup_ramp_s = 0.5;
  double shutdown_ramp_s = 0.02;       // a trip brings the force to zero within this
  double max_tick_interval_s = 0.005;  // a longer gap between ticks is a late tick (counted)
  // A longer gap is a stalled tick: trip. What the device holds meanwhile is bounded by this
  // (the derivation in docs/haptic-safety.md); the HapticMaster's I/O watchdog uses it too.
  double max_tick_stall_s = 0.1;
  int max_stale_ticks = 50;      // ticks without a new device sample: stalled
  std::string validate() const;  // empty when usable, else one line naming the option
};

enum class SafetyState { kStarting, kRunning, kRampingDown, kStopped };
std::string_view to_string(SafetyState state);

// Event bits (a tick may raise several).
enum SafetyEvent : std::uint32_t {
  kEventStartRampDone = 1u << 0,
  kEventForceLimited = 1u << 1,      // the limit started clipping (not raised again until
  kEventForceRateLimited = 1u << 2,  //   it has stopped clipping for a while)
  kEventVelocityTrip = 1u << 3,
  kEventWorkspaceTrip = 1u << 4,
  kEventDeadlineMiss = 1u << 5,
  kEventDeviceStalled = 1u << 6,
  kEventLinkLost = 1u << 7,
  kEventNonFiniteInput = 1u << 8,
  kEventPassivityActive = 1u << 9,  // the passivity controller started damping
  kEventStopRequested = 1u << 10,   // stop() asked for the ramp down
  kEventStopped = 1u << 11,         // the force has reached zero after a trip or stop
  kEventLateTick = 1u << 12,        // a gap above max_tick_interval_s: counted, not a trip
};
// The events that end a run: each begins the ramp down (a stop request does too, but it is
// asked for, not a fault).
inline constexpr std::uint32_t kTripEvents = kEventVelocityTrip | kEventWorkspaceTrip |
                                             kEventDeadlineMiss | kEventDeviceStalled |
                                             kEventLinkLost | kEventNonFiniteInput;
// "velocity_trip", "deadline_miss", ... for a single bit; "" otherwise.
std::string_view event_name(std::uint32_t single_event_bit);
// A sentence for the session's event detail, e.g. what the limit is.
std::string_view event_meaning(std::uint32_t single_event_bit);

// What a tick's record shows of the moment an event began: enough to give a trip its figure.
struct EventFacts {
  double interval_s = 0.0;  // since the previous tick (NaN when there was none)
  DeviceSample sample;      // the reading the tick acted on
  int stale_ticks = 0;      // ticks in a row whose reading had the same sequence number
};

struct SafetyInput {
  double time_s = 0.0;                // this tick's time
  DeviceSample sample;                // this tick's reading
  Vec3 desired_force = Vec3::Zero();  // model + constraint, device frame
};

struct SafetyOutput {
  Vec3 force = Vec3::Zero();  // what to command
  double scale = 0.0;         // the ramp's factor now, 0..1
  std::uint32_t events = 0;   // SafetyEvent bits that began this tick
  SafetyState state = SafetyState::kStarting;
  bool clipped = false;  // force or rate limit acted this tick
};

class SafetyLayer {
 public:
  // Throws std::invalid_argument with validate()'s message.
  SafetyLayer(const SafetyOptions& options, const DeviceLimits& limits);

  SafetyOutput step(const SafetyInput& input) noexcept;
  // Ramp down and stop (the user pressed stop, the run's time is up); raises
  // kEventStopRequested once.
  void request_stop() noexcept;
  SafetyState state() const noexcept { return state_; }
  double force_limit() const noexcept { return force_limit_; }
  double velocity_trip() const noexcept { return velocity_trip_; }
  // One line for the session and the user: event_name(bit), then the event's figure against
  // its limit where it has one ("velocity_trip: the device moved at 1.23 m/s, above the trip
  // speed of 1 m/s (velocity_trip, or the device's max_velocity)"), else event_meaning(bit).
  // Not real-time (it builds text); any thread: it reads only what the constructor set.
  std::string describe(std::uint32_t single_event_bit, const EventFacts& facts) const;
  double force_rate_limit() const noexcept { return force_rate_limit_; }

 private:
  SafetyOptions options_;
  DeviceLimits limits_;
  double force_limit_ = 0.0;
  double force_rate_limit_ = 0.0;
  SafetyState state_ = SafetyState::kStarting;
  // Implementation state (helper fills in).
  bool have_previous_ = false;
  double previous_time_s_ = 0.0;
  double start_time_s_ = 0.0;
  double ramp_down_start_s_ = 0.0;
  double ramp_down_from_scale_ = 1.0;
  double scale_ = 0.0;
  Vec3 previous_force_ = Vec3::Zero();
  std::uint64_t previous_sequence_ = 0;
  int stale_ticks_ = 0;
  int clipping_quiet_ticks_ = 0;
  bool clipping_ = false;
  bool stop_requested_ = false;
  bool stop_reported_ = false;
  // The rate limit's own clipping episode (force and rate are reported separately).
  int rate_quiet_ticks_ = 0;
  bool rate_clipping_ = false;
  double velocity_trip_ = 0.0;  // the smaller of the option and the device's max_velocity
  Vec3 ramp_down_from_force_ = Vec3::Zero();  // the force when the ramp down began
  double ramp_down_remaining_ = 1.0;          // only decreases, even if the clock steps back

  void begin_ramp_down(double time_s, std::uint32_t event, SafetyOutput& output) noexcept;
  SafetyOutput stopped_output(std::uint32_t events) noexcept;
  // step()'s stages; like it, none allocates, locks or throws.
  double advance_clock(double time_s, std::uint64_t sequence) noexcept;  // dt (0 at first)
  void check_trips(const SafetyInput& input, bool first_tick, double dt_s,
                   SafetyOutput& output) noexcept;
  void check_stale(double time_s, std::uint64_t sequence, SafetyOutput& output) noexcept;
  void check_motion(double time_s, const DeviceSample& sample, SafetyOutput& output) noexcept;
  SafetyOutput ramp_down(double time_s, SafetyOutput output) noexcept;
  void advance_start_ramp(double time_s, SafetyOutput& output) noexcept;
  Vec3 limit_force(const Vec3& desired_force, double dt_s, bool& force_clipped,
                   bool& rate_clipped) const noexcept;
  void report_clipping(bool force_clipped, bool rate_clipped, SafetyOutput& output) noexcept;
};

// Passivity observer and controller on the active terms (after Hannaford and Ryu). The
// observer integrates the energy the active terms put into the door (τ_active · ω dt); the
// energy they may inject is bounded by a budget that drains back at a set rate (so one snap
// per stroke is allowed, a limit cycle is not). When the observed energy exceeds the budget,
// the controller adds damping that dissipates the excess, bounded by max_damping.
struct PassivityOptions {
  bool enabled = true;
  double energy_budget_J = 0.5;    // what the active terms may inject before damping
  double budget_recovery_W = 0.5;  // the observed energy drains by this (not below 0)
  // Must exceed the largest negative damping a model may have (the snap's c, bounds up to
  // 50 N*m*s/rad), or the damping cannot cancel it and the energy is not bounded.
  double max_damping_Nm_s_per_rad = 60.0;
  std::string validate() const;
};

class PassivityController {
 public:
  explicit PassivityController(const PassivityOptions& options);  // throws invalid_argument
  // `active_torque_Nm`: the sum of the model's active terms this tick; returns the damping
  // torque to add (N*m, opposing ω). Raises kEventPassivityActive in `events` when it starts.
  double step(double active_torque_Nm, double omega_rad_s, double dt_s,
              std::uint32_t& events) noexcept;
  double observed_energy_J() const noexcept { return energy_J_; }
  double dissipated_energy_J() const noexcept { return dissipated_J_; }

 private:
  PassivityOptions options_;
  double energy_J_ = 0.0;
  double dissipated_J_ = 0.0;
  bool active_ = false;
};

// Checks a parameter set before it may reach the tick: every value finite and inside its
// bounds, and the stiffest restoring slope of τ_m over [θ_lo, θ_hi] (including the latch's
// switch edges), as device stiffness, below what the loop can render stably at its period
// with the device's inertia (the bound and its derivation in docs/haptic-safety.md).
// Returns "" when the set may be played, else one line naming the parameter or the slope.
// Throws std::invalid_argument naming the argument when device_inertia or tick_period_s is
// not > 0 or the angle range is empty or not finite.
std::string check_parameter_set(const DoorModel& model, const DoorMapping& mapping,
                                double device_inertia, double tick_period_s, double theta_lo_rad,
                                double theta_hi_rad);
// The same for new values of `model`'s parameters (what live tuning sends), checked before a
// model is built from them: `values` in parameter_values()'s order.
std::string check_parameter_values(const DoorModel& model, std::span<const double> values,
                                   const DoorMapping& mapping, double device_inertia,
                                   double tick_period_s, double theta_lo_rad, double theta_hi_rad);

// The stiffest restoring slope of τ_m at ω = 0 over [θ_lo, θ_hi] (a grid refined where the
// slope or the torque changes fast, so that switch edges of width 1/β are resolved).
struct RestoringSlope {
  double slope_Nm_per_rad = 0.0;  // max(−∂τ/∂θ), 0 when τ_m nowhere restores
  double theta_rad = 0.0;         // where
  int evaluations = 0;            // how many points the search took
};
RestoringSlope stiffest_restoring_slope(const DoorModel& model, double theta_lo_rad,
                                        double theta_hi_rad);
// The largest device stiffness (N/m; rotary: N*m/rad) the tick can render on an admittance
// device of inertia `device_inertia` (kg; rotary: kg*m^2) at `tick_period_s` (derivation in
// docs/haptic-safety.md): K_max = (4 ζ_max / 3)² m / T² with ζ_max = kMaxRequiredDampingRatio.
inline constexpr double kMaxRequiredDampingRatio = 0.1;
double stiffness_bound(double device_inertia, double tick_period_s) noexcept;

}  // namespace doorbench::haptic
