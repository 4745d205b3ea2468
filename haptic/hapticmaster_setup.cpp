// The HapticMaster's set-up steps, run by prepare() before the render loop starts: the
// device identified, its emergency signals and calibration checked, old effects cleared,
// the workspace read, the inertia set and read back, and the device-side elements (bias
// force, radial spring, end-stop walls, damper) created. Each step throws DeviceError
// naming the command and the reply at fault.
#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/clock.h"
#include "haptic/door_mapping.h"
#include "haptic/hapticmaster_connection.h"
#include "haptic/hapticmaster_device.h"
#include "haptic/hapticmaster_limits.h"
#include "haptic/hapticmaster_protocol.h"

namespace doorbench::haptic {

namespace {

// The reply's word: a quoted string's content, else the plain text.
std::string word_of(const hm::Reply& reply) {
  return reply.kind == hm::Reply::Kind::kString ? reply.string : reply.text;
}

// "true"/"false" (quoted or not, any case; also 1/0) -> bool; nullopt otherwise.
std::optional<bool> parse_flag(const std::string& reply_text) {
  std::string word = word_of(hm::parse_reply(reply_text));
  std::transform(word.begin(), word.end(), word.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (word == "true" || word == "1") return true;
  if (word == "false" || word == "0") return false;
  return std::nullopt;
}

}  // namespace

void HapticMasterDevice::identify() {
  // Does it answer at all, and with a state name, quoted or not? (A wrong server fails.)
  const hm::Reply state = hm::parse_reply(expect_ok("get state"));
  const std::string word = word_of(state);
  if ((state.kind != hm::Reply::Kind::kString && state.kind != hm::Reply::Kind::kMessage) ||
      word.empty() || !std::all_of(word.begin(), word.end(), [](char c) {
        return std::isalpha(static_cast<unsigned char>(c)) || c == '_';
      })) {
    throw DeviceError(name() + ": 'get state' answered '" + state.text +
                      "', not a state name: is this a HapticMaster?");
  }
  startup_.initial_state = word;
}

void HapticMasterDevice::check_emergency_signals() {
  // Each signal is "true" or "false"; a device that does not know the query (the public
  // clients ask only devices that report a Linux controller) answers with an error, which
  // is kept as "not reported" rather than refused.
  const auto flag = [&](const std::string& command) -> std::optional<bool> {
    const std::vector<std::string> replies = round_trip_one(command);
    if (replies.size() != 1) {
      throw DeviceError(name() + ": " + hm::check_replies({command}, replies));
    }
    if (hm::parse_reply(replies.front()).kind == hm::Reply::Kind::kError) return std::nullopt;
    const std::optional<bool> value = parse_flag(replies.front());
    if (!value) {
      throw DeviceError(name() + ": '" + command + "' answered '" + replies.front() +
                        "', not true or false");
    }
    return value;
  };
  const std::optional<bool> button = flag("get emergencybuttonpushed");
  startup_.emergency_button = button.value_or(false);
  startup_.emergency_signals_reported = button.has_value();
  if (startup_.emergency_button) {
    throw DeviceError(name() + ": the emergency button is pushed: release it, then start again");
  }
  // The relay is "true" while the device's power stage is armed; "false": it was not started
  // with its start button (or an emergency stop opened it).
  const std::optional<bool> relay = flag("get emergencyrelay");
  startup_.emergency_relay_closed = relay.value_or(true);
  startup_.emergency_signals_reported = startup_.emergency_signals_reported && relay.has_value();
  if (!startup_.emergency_relay_closed) {
    throw DeviceError(name() +
                      ": the emergency relay is open: the HapticMaster is not started (push its "
                      "start button), then start again");
  }
}

void HapticMasterDevice::ensure_calibrated() {
  const auto calibrated = [&] {
    const std::string reply = expect_ok("get position_calibrated");
    const std::optional<bool> value = parse_flag(reply);
    if (!value) {
      throw DeviceError(name() + ": 'get position_calibrated' answered '" + reply +
                        "', not true or false");
    }
    return *value;
  };
  startup_.was_calibrated = calibrated();
  if (startup_.was_calibrated) return;
  // Homing: the device moves to its end stops by itself; keep hands off the end-effector. It
  // has ended when the state is "stop" (what the public clients wait for) and the position is
  // calibrated.
  const auto say = [&](const std::string& line) {
    if (options_.progress) options_.progress(line);
  };
  say(name() + ": position not calibrated: homing (set state init); keep clear of the arm");
  const double began_s = monotonic_now_s();
  expect_ok("set state init");
  double next_report_s = began_s + 1.0;
  for (;;) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    const double now = monotonic_now_s();
    if (word_of(hm::parse_reply(expect_ok("get state"))) == "stop" && calibrated()) break;
    if (now - began_s > options_.homing_timeout_s) {
      throw DeviceError(name() + ": homing did not end within " +
                        hm::format_device_number(options_.homing_timeout_s) +
                        " s (no state 'stop' with the position calibrated)");
    }
    if (now >= next_report_s) {
      say(name() + ": homing ... " + hm::format_device_number(std::round(now - began_s)) + " s");
      next_report_s += 1.0;
    }
  }
  startup_.homing_s = monotonic_now_s() - began_s;
  say(name() + ": homing done in " +
      hm::format_device_number(std::round(startup_.homing_s * 10) / 10) + " s");
}

void HapticMasterDevice::clear_effects() {
  // Effects left by another program (or a session that ended without stop()) would add their
  // forces to ours: remove every one.
  expect_ok("remove all");
}

void HapticMasterDevice::read_workspace() {
  // The replies as the public client that draws the workspace reads them
  // (docs/hapticmaster.md): workspace_r [x low stop, distance from the origin to the base
  // axis, x high stop] (m), workspace_phi [left, -, right] (rad), workspace_z [one height,
  // -, the other] (m; the sources disagree on which comes first, so the smaller is the lower).
  std::array<std::vector<double>, 3> values;
  const char* names[3] = {"workspace_r", "workspace_phi", "workspace_z"};
  for (int k = 0; k < 3; ++k) {
    const std::string command = std::string("get ") + names[k];
    // Not expect_ok(): a list of 2 numbers is a valid reply here, not a malformed vector.
    const std::vector<std::string> replies = round_trip_one(command);
    const std::string reply = replies.size() == 1 ? replies.front() : "";
    std::optional<std::vector<double>> numbers = hm::parse_numbers(reply);
    if (!numbers && replies.size() == 1 && hm::parse_reply(reply).kind == hm::Reply::Kind::kError) {
      throw DeviceError(name() + ": '" + command + "' failed: " + hm::parse_reply(reply).text);
    }
    const std::size_t need = k == 0 ? 3 : 2;
    if (!numbers || numbers->size() < need || numbers->size() > 3) {
      throw DeviceError(name() + ": '" + command + "' answered '" + reply + "', not " +
                        (k == 0 ? "[low,axis,high]" : "[a,b] or [a,-,b]"));
    }
    values[k] = *numbers;
  }
  const double axis_m = values[0][1];
  const double r_low = axis_m + values[0][0], r_high = axis_m + values[0][2];
  const double phi_a = values[1].front(), phi_b = values[1].back();
  const double z_a = values[2].front(), z_b = values[2].back();
  startup_.base_axis_offset_m = axis_m;
  startup_.workspace_r_phi_z_min = Vec3(r_low, std::min(phi_a, phi_b), std::min(z_a, z_b));
  startup_.workspace_r_phi_z_max = Vec3(r_high, std::max(phi_a, phi_b), std::max(z_a, z_b));
  DeviceLimits read = hapticmaster_limits();
  read.workspace_min = read.workspace_max = Vec3::Zero();
  const bool usable = axis_m > 0 && r_low >= 0 && r_high > r_low &&
                      startup_.workspace_r_phi_z_max.y() > startup_.workspace_r_phi_z_min.y() &&
                      startup_.workspace_r_phi_z_max.z() > startup_.workspace_r_phi_z_min.z();
  if (usable) {
    workspace_box(startup_.workspace_r_phi_z_min, startup_.workspace_r_phi_z_max, axis_m, read);
  }
  if (!usable || !(read.workspace_max.array() > read.workspace_min.array()).all()) {
    throw DeviceError(
        name() + ": the workspace the device reports (r " + hm::format_device_number(r_low) + ".." +
        hm::format_device_number(r_high) + " m about an axis " + hm::format_device_number(axis_m) +
        " m behind, phi " + hm::format_device_number(startup_.workspace_r_phi_z_min.y()) + ".." +
        hm::format_device_number(startup_.workspace_r_phi_z_max.y()) + " rad, z " +
        hm::format_device_number(startup_.workspace_r_phi_z_min.z()) + ".." +
        hm::format_device_number(startup_.workspace_r_phi_z_max.z()) + " m) holds no box");
  }
  limits_ = read;
  startup_.workspace_source = "device";
}

void HapticMasterDevice::set_inertia_checked(double inertia) {
  expect_ok("set inertia " + hm::format_device_number(inertia));
  const std::string reply = expect_ok("get inertia");
  const hm::Reply value = hm::parse_reply(reply);
  if (value.kind != hm::Reply::Kind::kNumber) {
    throw DeviceError(name() + ": 'get inertia' answered '" + reply + "', not a number");
  }
  startup_.inertia_read_back_kg = value.number;
  // Compared at the precision the reply carries ("10.9195" for 10.91954 is the same number
  // at six significant digits, C's %g); the number was sent with 6 decimals at most.
  if (!hm::agrees_at_reply_precision(inertia, value.text)) {
    throw DeviceError(name() + ": 'set inertia " + hm::format_device_number(inertia) +
                      "' was accepted but the device reports " + value.text + " kg");
  }
}

void HapticMasterDevice::create_bias_and_elements() {
  const std::string bias = options_.bias_object;
  expect_ok("create biasforce " + bias);
  bias_created_ = true;
  expect_ok("set " + bias + " force " + hm::format_vector(Vec3::Zero()));
  expect_ok("set " + bias + " enable");
  if (arc_) create_device_elements();
}

bool HapticMasterDevice::render_stiff_parts_on_device(const DoorMapping& mapping,
                                                      double theta_min_rad, double theta_max_rad) {
  if (io_thread_.joinable()) throw DeviceError(name() + ": stiff parts must be set before start");
  arc_ = &mapping;
  stop_theta_min_rad_ = theta_min_rad;
  stop_theta_max_rad_ = theta_max_rad;
  return true;
}

namespace {

// A spring's dampfactor for damping `c` (N*s/m) at stiffness k and mass m: the fraction of
// critical damping c / (2 sqrt(k m)) (dimensionless, docs/hapticmaster.md).
double damp_factor(double c, double k, double m) {
  return k > 0 && m > 0 ? c / (2.0 * std::sqrt(k * m)) : 0.0;
}

// How far a wall's spring sits behind its wall: the deadband that makes a symmetric spring
// one-sided (its other side lies this far beyond, outside the workspace).
constexpr double kStopDeadband_m = 0.5;

}  // namespace

std::vector<std::string> HapticMasterDevice::radial_spring_at(double theta_rad) const {
  return {"set doorbench_radial pos " + hm::format_vector(arc_->point_at(theta_rad)),
          "set doorbench_radial direction " + hm::format_vector(arc_->radial_at(theta_rad))};
}

void HapticMasterDevice::create_device_elements() {
  const ArcGeometry& g = arc_->geometry();
  const double m = startup_.inertia_read_back_kg;
  const std::string max_force = hm::format_device_number(options_.element_max_force_N);
  // Where the end-effector is now decides the radial spring's first angle.
  DeviceSample here;
  const hm::Reply position = hm::parse_reply(expect_ok("get measpos"));
  if (position.kind == hm::Reply::Kind::kVector) here.position = position.vector;
  const double theta =
      std::clamp(arc_->to_door(here).theta_rad, stop_theta_min_rad_, stop_theta_max_rad_);
  const auto spring = [&](const std::string& object, const Vec3& pos, const Vec3& direction,
                          double k, double factor, double deadband) {
    expect_ok("create spring " + object);
    elements_created_ = true;
    expect_ok("set " + object + " pos " + hm::format_vector(pos));
    expect_ok("set " + object + " direction " + hm::format_vector(direction));
    expect_ok("set " + object + " stiffness " + hm::format_device_number(k));
    expect_ok("set " + object + " dampfactor " + hm::format_device_number(factor));
    expect_ok("set " + object + " deadband " + hm::format_device_number(deadband));
    expect_ok("set " + object + " maxforce " + max_force);
    expect_ok("set " + object + " enable");
  };
  spring("doorbench_axial", g.hinge_point_m, g.hinge_axis.normalized(), g.axial_stiffness_N_per_m,
         damp_factor(g.axial_damping_N_s_per_m, g.axial_stiffness_N_per_m, m), 0.0);
  spring("doorbench_radial", arc_->point_at(theta), arc_->radial_at(theta),
         g.radial_stiffness_N_per_m,
         damp_factor(g.radial_damping_N_s_per_m, g.radial_stiffness_N_per_m, m), 0.0);
  // The walls: past θ_min the end-effector is pushed back along the arc's tangent there (its
  // spring sits kStopDeadband_m beyond the wall, inside the door's range), likewise at θ_max.
  const Vec3 t_closed = arc_->tangent_at(stop_theta_min_rad_);
  const Vec3 t_open = arc_->tangent_at(stop_theta_max_rad_);
  spring("doorbench_stop_closed", arc_->point_at(stop_theta_min_rad_) + kStopDeadband_m * t_closed,
         t_closed, options_.end_stop_stiffness_N_per_m, options_.end_stop_damping_ratio,
         kStopDeadband_m);
  spring("doorbench_stop_open", arc_->point_at(stop_theta_max_rad_) - kStopDeadband_m * t_open,
         t_open, options_.end_stop_stiffness_N_per_m, options_.end_stop_damping_ratio,
         kStopDeadband_m);
  expect_ok("create damper doorbench_damper");
  expect_ok("set doorbench_damper dampcoef " +
            hm::format_vector(Vec3::Constant(options_.device_damping_N_s_per_m)));
  expect_ok("set doorbench_damper enable");
}

}  // namespace doorbench::haptic
