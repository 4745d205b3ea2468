#pragma once
// The bring-up check for a HapticMaster (`doorbench hapticmaster check`, docs/hapticmaster.md):
// what a lab runs the first time it plugs in a device, before anyone plays a door on it.
//
//  1. start-up as the driver does it: identify the device, both emergency signals, position
//     calibration (homing when needed), "remove all", the workspace and the inertia read back;
//  2. round-trip time: `exchanges` round trips of the driver's loop at zero force (its real
//     traffic: the bias force and the three readings), p50/p99/max;
//  3. the stiffness the host loop can render stably with that delay (stiffness_limit below);
//  4. with the user's confirmation only (the arm is pushed gently): a bias force of
//     `test_force_N` is applied, the socket is closed as a crashed host would close it, and a
//     new connection reads back what the device still applies. A device that keeps the force
//     is reported (a warning: doorbench's fail-safe stops it on a fresh connection, but a
//     killed process or a host power loss would leave the force on), then stopped.
// The report lists every check with pass / warn / fail / skipped and the figures, as text and
// as JSON.
//
// Thread safety: one call at a time; it owns the device for its duration.
#include <functional>
#include <string>
#include <vector>

#include "haptic/hapticmaster_device.h"
#include "haptic/safety.h"

namespace doorbench::haptic {

struct HapticMasterCheckOptions {
  int exchanges = 3000;       // round trips timed
  double inertia_kg = 10.0;   // rendered during the check (heavy: the arm barely moves)
  double test_force_N = 2.0;  // the disconnect test's bias force
  double damping_ratio = kMaxRequiredDampingRatio;  // for the stiffness limit
  HapticMasterOptions driver;                       // timeouts, rate, progress lines
  // Asked before the disconnect test with a sentence saying what will happen; true = go on.
  // Unset: the test is skipped.
  std::function<bool(const std::string&)> confirm;
  std::string validate() const;  // "" or one line naming the option
};

struct HapticMasterCheckItem {
  std::string name;    // "emergency button", "round-trip time", ...
  std::string status;  // "pass", "warn", "fail", "skipped"
  std::string detail;  // one line
};

struct HapticMasterCheckReport {
  std::string device;  // hapticmaster://host:port
  HapticMasterStartup startup;
  DeviceLimits limits;  // as read from the device
  int round_trips = 0;
  double rtt_p50_ms = 0.0, rtt_p99_ms = 0.0, rtt_max_ms = 0.0, rtt_mean_ms = 0.0;
  double loop_period_ms = 0.0;           // the driver's I/O period
  double effective_delay_ms = 0.0;       // half a period (hold) + the p99 round trip
  double stiffness_limit_N_per_m = 0.0;  // at inertia_kg, for the host-side loop
  bool disconnect_tested = false;
  double force_after_disconnect_N = 0.0;  // what the device still applied, if tested
  std::string state_after_disconnect;
  std::vector<HapticMasterCheckItem> items;

  bool passed() const;  // no item failed
  std::string text() const;
  std::string json() const;  // a JSON object with every field above
};

// The stiffness a sampled host loop renders stably on an admittance device of inertia
// `inertia_kg` with an effective delay `delay_s` (hold plus round trip): 4 ζ² m / τ², the
// safety layer's bound (stiffness_bound) with its 1.5 periods of delay replaced by τ.
double stiffness_limit_for_delay(double inertia_kg, double delay_s, double damping_ratio) noexcept;

// Runs the check against `address` ("host[:port]"). Throws DeviceError when the device cannot
// be reached or refuses to start (the message names the step); every other finding is an
// item of the report.
HapticMasterCheckReport run_hapticmaster_check(const std::string& address,
                                               const HapticMasterCheckOptions& options);

}  // namespace doorbench::haptic
