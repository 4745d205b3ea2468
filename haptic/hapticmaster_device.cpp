#include "haptic/hapticmaster_device.h"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/clock.h"
#include "haptic/door_mapping.h"
#include "haptic/hapticmaster_connection.h"
#include "haptic/hapticmaster_limits.h"
#include "haptic/hapticmaster_protocol.h"

namespace doorbench::haptic {
namespace {

using Clock = std::chrono::steady_clock;

// "" if `replies` answer `commands` without error, else what went wrong: the first error
// reply (named by its command) or a wrong count.
std::string check_replies(const std::vector<std::string>& commands,
                          const std::vector<std::string>& replies) {
  for (std::size_t i = 0; i < replies.size(); ++i) {
    const hm::Reply reply = hm::parse_reply(replies[i]);
    if (reply.kind == hm::Reply::Kind::kError) {
      const std::string& command = i < commands.size() ? commands[i] : commands.back();
      return "'" + command + "' failed: " + reply.text;
    }
  }
  if (replies.size() != commands.size()) {
    return std::to_string(commands.size()) + " command(s) '" + hm::join_commands(commands) +
           "' answered with " + std::to_string(replies.size()) + " repl" +
           (replies.size() == 1 ? "y" : "ies");
  }
  return "";
}

// The readings at the end of a round trip: checks the replies, then takes the last three
// (measpos, modelvel, measforce) into `sample`. Returns "" or what went wrong.
std::string take_readings(const std::vector<std::string>& commands,
                          const std::vector<std::string>& replies, DeviceSample& sample) {
  if (std::string problem = check_replies(commands, replies); !problem.empty()) return problem;
  Vec3* fields[3] = {&sample.position, &sample.velocity, &sample.measured_force};
  for (std::size_t k = 0; k < 3; ++k) {
    const std::size_t i = commands.size() - 3 + k;
    const hm::Reply reply = hm::parse_reply(replies[i]);
    if (reply.kind != hm::Reply::Kind::kVector) {
      return "'" + commands[i] + "' answered '" + reply.text + "', not [x,y,z]";
    }
    *fields[k] = reply.vector;
  }
  return "";
}

const std::vector<std::string> kReadings = {"get measpos", "get modelvel", "get measforce"};

}  // namespace


std::string HapticMasterOptions::validate() const {
  if (!(connect_timeout_s > 0) || !std::isfinite(connect_timeout_s)) {
    return "connect_timeout_s must be > 0";
  }
  if (!(reply_timeout_s > 0) || !std::isfinite(reply_timeout_s)) {
    return "reply_timeout_s must be > 0";
  }
  if (!(io_rate_hz > 0) || !(io_rate_hz <= 10000)) return "io_rate_hz must be in (0, 10000]";
  if (io_fifo_priority < 0 || io_fifo_priority > 99) {
    return "io_fifo_priority must be in [0, 99] (0: best effort)";
  }
  if (bias_object.empty() || !std::all_of(bias_object.begin(), bias_object.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
      })) {
    return "bias_object must be a non-empty name of letters, digits and '_'";
  }
  if (!(emergency_timeout_s > 0) || !(emergency_timeout_s <= 5)) {
    return "emergency_timeout_s must be in (0, 5] s";
  }
  if (!(command_watchdog_s >= 0) || !std::isfinite(command_watchdog_s)) {
    return "command_watchdog_s must be >= 0 (0 = off)";
  }
  if (!(first_command_timeout_s > 0) || !std::isfinite(first_command_timeout_s)) {
    return "first_command_timeout_s must be > 0";
  }
  if (!(homing_timeout_s > 0) || !std::isfinite(homing_timeout_s)) {
    return "homing_timeout_s must be > 0";
  }
  if (!(device_damping_N_s_per_m >= 0) || !(device_damping_N_s_per_m <= 1000)) {
    return "device_damping_N_s_per_m must be in [0, 1000]";
  }
  if (!(end_stop_stiffness_N_per_m > 0) || !(end_stop_stiffness_N_per_m <= 1e6)) {
    return "end_stop_stiffness_N_per_m must be in (0, 1e6]";
  }
  if (!(end_stop_damping_ratio >= 0) || !(end_stop_damping_ratio <= 2)) {
    return "end_stop_damping_ratio must be in [0, 2]";
  }
  if (!(element_max_force_N > 0) || !(element_max_force_N <= 250)) {
    return "element_max_force_N must be in (0, 250]";
  }
  return "";
}

HapticMasterDevice::HapticMasterDevice(const std::string& address, HapticMasterOptions options)
    : options_(std::move(options)), limits_(hapticmaster_limits()) {
  try {
    const hm::Address parsed = hm::parse_address(address);
    host_ = parsed.host;
    port_ = parsed.port;
  } catch (const std::invalid_argument& e) {
    throw DeviceError(std::string("hapticmaster://").append(address).append(": ").append(e.what()));
  }
  if (const std::string problem = options_.validate(); !problem.empty()) {
    throw DeviceError(name() + ": option " + problem);
  }
  startup_.workspace_source = "assumed (not started)";
  round_trip_times_s_.reserve(kRoundTripLog);
}

HapticMasterDevice::~HapticMasterDevice() {
  stop();
}

std::string HapticMasterDevice::name() const {
  return "hapticmaster://" + host_ + ":" + std::to_string(port_);
}

DeviceLimits HapticMasterDevice::limits() const {
  return limits_;
}

std::vector<std::string> HapticMasterDevice::round_trip_one(const std::string& command) {
  try {
    return connection_->round_trip({command}, options_.reply_timeout_s, true);
  } catch (const std::exception& e) {
    connection_intact_ = false;
    throw DeviceError(name() + ": '" + command + "': " + e.what());
  }
}

std::string HapticMasterDevice::expect_ok(const std::string& command) {
  const std::vector<std::string> replies = round_trip_one(command);
  if (const std::string problem = check_replies({command}, replies); !problem.empty()) {
    throw DeviceError(name() + ": " + problem);
  }
  return replies.front();
}

std::string HapticMasterDevice::exchange(const std::string& command) {
  if (io_thread_.joinable()) throw DeviceError(name() + ": exchange() while the I/O thread runs");
  if (!connection_ || !connection_intact_) throw DeviceError(name() + ": not connected");
  return expect_ok(command);
}

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
      throw DeviceError(name() + ": " + check_replies({command}, replies));
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
    throw DeviceError(name() +
                      ": the emergency button is pushed: release it, then start again");
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
    if (!numbers && replies.size() == 1 &&
        hm::parse_reply(reply).kind == hm::Reply::Kind::kError) {
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
    throw DeviceError(name() + ": the workspace the device reports (r " +
                      hm::format_device_number(r_low) + ".." + hm::format_device_number(r_high) +
                      " m about an axis " + hm::format_device_number(axis_m) + " m behind, phi " +
                      hm::format_device_number(startup_.workspace_r_phi_z_min.y()) + ".." +
                      hm::format_device_number(startup_.workspace_r_phi_z_max.y()) + " rad, z " +
                      hm::format_device_number(startup_.workspace_r_phi_z_min.z()) + ".." +
                      hm::format_device_number(startup_.workspace_r_phi_z_max.z()) +
                      " m) holds no box");
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

DeviceSample HapticMasterDevice::first_reading() {
  // The first reading, so the tick's first read() has a real position (sequence 1).
  std::vector<std::string> replies;
  try {
    replies = connection_->round_trip(kReadings, options_.reply_timeout_s, options_.join_commands);
  } catch (const std::exception& e) {
    connection_intact_ = false;
    throw DeviceError(name() + ": first reading: " + e.what());
  }
  DeviceSample first;
  first.time_s = monotonic_now_s();
  if (const std::string problem = take_readings(kReadings, replies, first); !problem.empty()) {
    throw DeviceError(name() + ": " + problem);
  }
  first.sequence = 1;
  first.link_ok = true;
  return first;
}

void HapticMasterDevice::prepare(double inertia) {
  if (io_thread_.joinable() || connection_) throw DeviceError(name() + ": already started");
  const DeviceLimits assumed = hapticmaster_limits();
  if (!(inertia >= assumed.min_inertia && inertia <= assumed.max_inertia)) {
    throw DeviceError(name() + ": inertia " +
                      hm::format_device_number(std::isfinite(inertia) ? inertia : 0) +
                      " kg is outside " + hm::format_device_number(assumed.min_inertia) + ".." +
                      hm::format_device_number(assumed.max_inertia) + " kg");
  }
  try {
    connection_ = std::make_unique<hm::Connection>(host_, port_, options_.connect_timeout_s);
  } catch (const std::exception& e) {
    throw DeviceError(name() + ": " + e.what());
  }
  connection_intact_ = true;
  bias_created_ = false;
  elements_created_ = false;
  device_stopped_.store(false);
  brake_requested_.store(false);
  {
    std::lock_guard<std::mutex> lock(error_mutex_);
    last_error_.clear();
  }
  startup_ = HapticMasterStartup{};
  startup_.workspace_source = "assumed (start failed before the workspace was read)";
  guarded([&] {
    identify();
    check_emergency_signals();
    ensure_calibrated();
    clear_effects();
    read_workspace();
    set_inertia_checked(inertia);
    create_bias_and_elements();
  });
  prepared_inertia_ = inertia;
}

void HapticMasterDevice::guarded(const std::function<void()>& steps) {
  try {
    steps();
  } catch (...) {
    // Leave the device as stop() would: zero force and "stop", whatever step failed.
    send_shutdown();
    link_ok_.store(false);
    connection_.reset();
    connection_intact_ = false;
    prepared_inertia_ = kNaN;
    throw;
  }
}

void HapticMasterDevice::start(double inertia) {
  if (io_thread_.joinable()) throw DeviceError(name() + ": already started");
  if (std::isnan(prepared_inertia_)) prepare(inertia);
  DeviceSample first;
  guarded([&] {
    if (inertia != prepared_inertia_) set_inertia_checked(inertia);
    expect_ok("set state force");
    first = first_reading();
  });
  prepared_inertia_ = kNaN;

  staged_ = Command{Vec3::Zero(), inertia};
  commands_.back() = staged_;
  commands_.publish();
  samples_.back() = first;
  samples_.publish();
  last_read_ = first;
  round_trips_.store(0);
  first_command_arrival_s_.store(kNaN, std::memory_order_release);
  round_trip_times_s_.clear();
  round_trip_next_ = 0;
  stop_requested_.store(false);
  link_ok_.store(true);
  io_thread_ = std::thread([this, inertia, first] { io_loop(inertia, first); });
  io_thread_fifo_ = false;
  if (options_.io_fifo_priority > 0) {
    sched_param parameter{};
    parameter.sched_priority = options_.io_fifo_priority;
    io_thread_fifo_ =
        pthread_setschedparam(io_thread_.native_handle(), SCHED_FIFO, &parameter) == 0;
  }
}

void HapticMasterDevice::fail(const std::string& reason) {
  link_ok_.store(false);
  std::lock_guard<std::mutex> lock(error_mutex_);
  if (last_error_.empty()) last_error_ = name() + ": " + reason;
}

std::string HapticMasterDevice::emergency_stop(bool connection_intact) noexcept {
  const std::vector<std::string> commands = {
      "set " + options_.bias_object + " force " + hm::format_vector(Vec3::Zero()),
      "set state stop"};
  // "set state stop" answered without error is what counts: the zero force may fail if the
  // bias object is gone (another program removed it), and then there is no force to zero.
  const auto stopped_by = [&](const std::vector<std::string>& replies) {
    return replies.size() == commands.size() &&
           hm::parse_reply(replies[1]).kind != hm::Reply::Kind::kError;
  };
  std::string why;
  if (connection_ && connection_intact) {
    try {
      if (stopped_by(connection_->round_trip(commands, options_.emergency_timeout_s,
                                             options_.join_commands))) {
        device_stopped_.store(true);
        return "";
      }
      why = "the open connection: 'set state stop' was refused";
    } catch (const std::exception& e) {
      why = std::string("the open connection: ").append(e.what());
      connection_intact_ = false;
    }
  }
  // A fresh connection: close the old one first (a device may take one client at a time).
  connection_.reset();
  connection_intact_ = false;
  try {
    hm::Connection fresh(host_, port_, options_.emergency_timeout_s);
    if (stopped_by(fresh.round_trip(commands, options_.emergency_timeout_s,
                                    options_.join_commands))) {
      device_stopped_.store(true);
      return "";
    }
    why +=
        (why.empty() ? "" : "; ") + std::string("a fresh connection: 'set state stop' was refused");
  } catch (const std::exception& e) {
    why += (why.empty() ? "" : "; ") + std::string("a fresh connection: ").append(e.what());
  }
  return why;
}

void HapticMasterDevice::lose_link(const std::string& reason, bool connection_intact,
                                   DeviceSample sample) noexcept {
  const std::string unreached = emergency_stop(connection_intact);
  fail(reason + (unreached.empty()
                     ? "; the device was stopped (zero force, state stop)"
                     : "; the emergency stop did not reach the device (" + unreached +
                           "): it may still apply its last force"));
  sample.link_ok = false;
  samples_.back() = sample;
  samples_.publish();
}

std::string HapticMasterDevice::watchdog_verdict(bool armed, double started_s,
                                                 double last_command_s) const {
  const double now_s = monotonic_now_s();
  const auto seconds = [](double s) {
    return hm::format_device_number(std::round(s * 1000) / 1000);
  };
  if (!armed) {
    if (now_s - started_s <= options_.first_command_timeout_s) return "";
    return "watchdog: the render loop sent no first command within " + seconds(now_s - started_s) +
           " s of the device's start (limit " +
           hm::format_device_number(options_.first_command_timeout_s) + " s)";
  }
  const double silent_s = now_s - last_command_s;
  if (options_.command_watchdog_s <= 0 || silent_s <= options_.command_watchdog_s) return "";
  return "watchdog: the render loop sent no command for " + seconds(silent_s) + " s (limit " +
         hm::format_device_number(options_.command_watchdog_s) + " s)";
}

void HapticMasterDevice::io_loop(double sent_inertia, DeviceSample sample) {
  const DeviceLimits limits = limits_;
  const std::string set_force = "set " + options_.bias_object + " force ";
  std::vector<std::string> commands;
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / options_.io_rate_hz));
  auto next = Clock::now();
  const double started_s = monotonic_now_s();
  // The watchdog arms at the render loop's first command; until then the device holds the
  // zero force start() left and only the first-command limit applies.
  bool armed = false;
  double last_command_s = started_s;
  double radial_theta = arc_ ? arc_->to_door(sample).theta_rad : 0.0;
  for (;;) {
    if (commands_.update()) {
      last_command_s = monotonic_now_s();
      armed = armed || commands_.front().serial > 0;
    }
    // A brake asked before the stop is done first: stop() may follow the tick's brake() before
    // this thread wakes, and the device's own brake must still come before the shutdown.
    if (brake_requested_.load(std::memory_order_acquire)) {
      // The safety layer tripped on motion (or stopped): zero force and the device's brake,
      // then no more exchanges; stop() removes the bias object later.
      if (const std::string unreached = emergency_stop(connection_intact_); !unreached.empty()) {
        fail("brake: the emergency stop did not reach the device (" + unreached + ")");
      }
      sample.link_ok = false;
      samples_.back() = sample;
      samples_.publish();
      link_ok_.store(false);
      return;
    }
    if (stop_requested_.load(std::memory_order_acquire)) return;
    if (const std::string silence = watchdog_verdict(armed, started_s, last_command_s);
        !silence.empty()) {
      lose_link(silence, connection_intact_, sample);
      return;
    }
    const Command command = commands_.front();
    Vec3 force = command.force;
    if (!force.allFinite()) force = Vec3::Zero();
    const double norm = force.norm();
    if (norm > limits.max_force) force *= limits.max_force / norm;
    commands.clear();
    commands.push_back(set_force + hm::format_vector(force));
    const bool new_inertia = command.inertia != sent_inertia;
    if (new_inertia) commands.push_back("set inertia " + hm::format_device_number(command.inertia));
    if (arc_) {  // the radial spring follows the door (a milliradian moves it)
      const double theta = std::clamp(arc_->to_door(sample).theta_rad,
                                      stop_theta_min_rad_ - 0.05, stop_theta_max_rad_ + 0.05);
      if (std::abs(theta - radial_theta) > 1e-3) {
        for (std::string& move : radial_spring_at(theta)) commands.push_back(std::move(move));
        radial_theta = theta;
      }
    }
    commands.insert(commands.end(), kReadings.begin(), kReadings.end());
    std::string problem;
    bool intact = true;
    try {
      const double sent_s = monotonic_now_s();
      const std::vector<std::string> replies =
          connection_->round_trip(commands, options_.reply_timeout_s, options_.join_commands);
      const double now_s = monotonic_now_s();
      DeviceSample reading = sample;
      problem = take_readings(commands, replies, reading);
      if (problem.empty()) {
        if (new_inertia) sent_inertia = command.inertia;
        if (command.serial > 0 && std::isnan(first_command_arrival_s_.load())) {
          first_command_arrival_s_.store(now_s, std::memory_order_release);
        }
        sample = reading;
        sample.time_s = now_s;
        ++sample.sequence;
        sample.link_ok = true;
        samples_.back() = sample;
        samples_.publish();
        round_trips_.fetch_add(1, std::memory_order_relaxed);
        if (round_trip_times_s_.size() < kRoundTripLog) {
          round_trip_times_s_.push_back(now_s - sent_s);
        } else {
          round_trip_times_s_[round_trip_next_] = now_s - sent_s;
        }
        round_trip_next_ = (round_trip_next_ + 1) % kRoundTripLog;
      }
    } catch (const std::exception& e) {
      problem = e.what();
      intact = false;  // closed, corrupt or silent: this stream cannot be trusted again
    }
    if (!problem.empty()) {
      if (!intact) connection_intact_ = false;
      lose_link(problem, intact, sample);
      return;  // the render loop ramps down and stops; no reconnecting mid-session
    }
    next += period;
    const auto now = Clock::now();
    if (next < now) {
      next = now;  // the link is slower than the rate: go on at once, don't burst later
    } else {
      std::this_thread::sleep_until(next);
    }
  }
}

void HapticMasterDevice::stop() noexcept {
  stop_requested_.store(true, std::memory_order_release);
  if (io_thread_.joinable()) io_thread_.join();
  if (connection_ || bias_created_) send_shutdown();
  connection_.reset();
  connection_intact_ = false;
  link_ok_.store(false);
}

void HapticMasterDevice::connect_only() {
  if (io_thread_.joinable() || connection_) throw DeviceError(name() + ": already connected");
  try {
    connection_ = std::make_unique<hm::Connection>(host_, port_, options_.connect_timeout_s);
  } catch (const std::exception& e) {
    throw DeviceError(name() + ": " + e.what());
  }
  connection_intact_ = true;
  bias_created_ = true;  // whatever a crashed session left: stop() zeroes and removes it
  device_stopped_.store(false);
}

void HapticMasterDevice::abandon_connection_for_test() noexcept {
  stop_requested_.store(true, std::memory_order_release);
  if (io_thread_.joinable()) io_thread_.join();
  connection_.reset();
  connection_intact_ = false;
  bias_created_ = false;
  link_ok_.store(false);
}

void HapticMasterDevice::send_shutdown() noexcept {
  if (!connection_ && !bias_created_) return;
  const std::string bias = options_.bias_object;
  std::vector<std::string> commands = {"set " + bias + " force " + hm::format_vector(Vec3::Zero()),
                                       "set state stop", "remove " + bias};
  if (elements_created_) {
    for (const char* object : {"doorbench_axial", "doorbench_radial", "doorbench_stop_closed",
                               "doorbench_stop_open", "doorbench_damper"}) {
      commands.push_back(std::string("remove ") + object);
    }
  }
  if (connection_ && connection_intact_) {
    try {
      const auto replies =
          connection_->round_trip(commands, options_.reply_timeout_s, options_.join_commands);
      // The force (if the object still exists) and the state are what matter.
      if (replies.size() == commands.size() &&
          hm::parse_reply(replies[1]).kind != hm::Reply::Kind::kError) {
        device_stopped_.store(true);
        bias_created_ = false;
        elements_created_ = false;
        if (const std::string problem = check_replies(commands, replies); !problem.empty()) {
          fail(problem);
        }
        return;
      }
      if (const std::string problem = check_replies(commands, replies); !problem.empty()) {
        fail(problem);
      }
    } catch (const std::exception& e) {
      fail("stop: " + std::string(e.what()));
      connection_intact_ = false;
    }
  }
  if (device_stopped_.load()) return;  // a failure already stopped it
  if (const std::string unreached = emergency_stop(false); !unreached.empty()) {
    fail("stop: the device could not be reached to zero its force (" + unreached + ")");
  }
}

DeviceSample HapticMasterDevice::read() noexcept {
  if (samples_.update()) last_read_ = samples_.front();
  return last_read_;
}

void HapticMasterDevice::command_force(const Vec3& force) noexcept {
  staged_.force = force;
  ++staged_.serial;
  commands_.back() = staged_;
  commands_.publish();
}

void HapticMasterDevice::command_inertia(double inertia) noexcept {
  if (!std::isfinite(inertia)) return;
  staged_.inertia = std::clamp(inertia, limits_.min_inertia, limits_.max_inertia);
  ++staged_.serial;
  commands_.back() = staged_;
  commands_.publish();
}

void HapticMasterDevice::brake() noexcept {
  brake_requested_.store(true, std::memory_order_release);
}

std::vector<double> HapticMasterDevice::round_trip_times_s() const {
  if (round_trip_times_s_.size() < kRoundTripLog) return round_trip_times_s_;
  std::vector<double> ordered(round_trip_times_s_.begin() + static_cast<long>(round_trip_next_),
                              round_trip_times_s_.end());
  ordered.insert(ordered.end(), round_trip_times_s_.begin(),
                 round_trip_times_s_.begin() + static_cast<long>(round_trip_next_));
  return ordered;
}

std::string HapticMasterDevice::last_error() const {
  std::lock_guard<std::mutex> lock(error_mutex_);
  return last_error_;
}

}  // namespace doorbench::haptic
