#include "haptic/hapticmaster_device.h"

#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/clock.h"
#include "haptic/hapticmaster_connection.h"
#include "haptic/hapticmaster_limits.h"
#include "haptic/hapticmaster_protocol.h"

namespace doorbench::haptic {
namespace {

using Clock = std::chrono::steady_clock;

// The readings at the end of a round trip: checks the replies, then takes the last three
// (measpos, modelvel, measforce) into `sample`. Returns "" or what went wrong.
std::string take_readings(const std::vector<std::string>& commands,
                          const std::vector<std::string>& replies, DeviceSample& sample) {
  if (std::string problem = hm::check_replies(commands, replies); !problem.empty()) return problem;
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
  if (const std::string problem = hm::check_replies({command}, replies); !problem.empty()) {
    throw DeviceError(name() + ": " + problem);
  }
  return replies.front();
}

std::string HapticMasterDevice::exchange(const std::string& command) {
  if (io_thread_.joinable()) throw DeviceError(name() + ": exchange() while the I/O thread runs");
  if (!connection_ || !connection_intact_) throw DeviceError(name() + ": not connected");
  return expect_ok(command);
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
    if (stopped_by(
            fresh.round_trip(commands, options_.emergency_timeout_s, options_.join_commands))) {
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
  fail(reason + (unreached.empty() ? "; the device was stopped (zero force, state stop)"
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
      const double theta = std::clamp(arc_->to_door(sample).theta_rad, stop_theta_min_rad_ - 0.05,
                                      stop_theta_max_rad_ + 0.05);
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
        if (const std::string problem = hm::check_replies(commands, replies); !problem.empty()) {
          fail(problem);
        }
        return;
      }
      if (const std::string problem = hm::check_replies(commands, replies); !problem.empty()) {
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
