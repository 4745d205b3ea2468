#include "haptic/door_snapshot.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <thread>

namespace doorbench::haptic {

std::string DoorEventAngles::validate() const {
  if (!std::isnan(latch_rad) && !std::isfinite(latch_rad)) return "latch_rad must be finite";
  if (!std::isfinite(closed_stop_rad) || !std::isfinite(open_stop_rad) ||
      !(open_stop_rad > closed_stop_rad)) {
    return "open_stop_rad must be finite and above closed_stop_rad";
  }
  if (!(hysteresis_rad >= 0.0) || !(stop_zone_rad >= 0.0) || !(stop_rearm_rad > stop_zone_rad)) {
    return "hysteresis_rad and stop_zone_rad must be >= 0, stop_rearm_rad above stop_zone_rad";
  }
  if (!(min_stop_speed_rad_s >= 0.0)) return "min_stop_speed_rad_s must be >= 0";
  return "";
}

DoorEventAngles DoorEventAngles::for_model(const DoorModel& model) {
  DoorEventAngles angles;
  angles.open_stop_rad = model.geometry().theta_max_rad;
  const auto values = model.parameter_values();
  if (const auto theta1 = model.find_parameter("theta1")) {
    angles.latch_rad = values[*theta1];
  } else if (const auto h = model.find_parameter("h"), r = model.find_parameter("r_l");
             h && r && values[*r] > 0.0) {
    angles.latch_rad = values[*h] / values[*r];
  } else {
    angles.latch_rad = std::numeric_limits<double>::quiet_NaN();
  }
  return angles;
}

DoorSnapshotChannel::DoorSnapshotChannel(const DoorEventAngles& angles) : angles_(angles) {
  if (std::string problem = angles_.validate(); !problem.empty()) {
    throw std::invalid_argument("door snapshot: " + problem);
  }
  store(current_);
}

void DoorSnapshotChannel::publish(double time_s, double theta_rad, double omega_rad_s) noexcept {
  DoorSnapshot& s = current_;
  const DoorEventAngles& a = angles_;
  if (first_) {
    // The door starts where it is: no event for the first tick's side of the latch.
    latched_ = !(theta_rad > a.latch_rad);
    first_ = false;
  }
  if (!std::isnan(a.latch_rad)) {
    if (latched_ && theta_rad > a.latch_rad + a.hysteresis_rad) {
      latched_ = false;
      ++s.unlatches;
      s.last_latch_event_time_s = time_s;
    } else if (!latched_ && theta_rad < a.latch_rad - a.hysteresis_rad) {
      latched_ = true;
      ++s.latches;
      s.last_latch_event_time_s = time_s;
    }
  }
  if (open_armed_ && theta_rad > a.open_stop_rad - a.stop_zone_rad &&
      omega_rad_s > a.min_stop_speed_rad_s) {
    open_armed_ = false;
    ++s.open_stop_hits;
    s.last_stop_speed_rad_s = std::abs(omega_rad_s);
  } else if (theta_rad < a.open_stop_rad - a.stop_rearm_rad) {
    open_armed_ = true;
  }
  if (closed_armed_ && theta_rad < a.closed_stop_rad + a.stop_zone_rad &&
      omega_rad_s < -a.min_stop_speed_rad_s) {
    closed_armed_ = false;
    ++s.closed_stop_hits;
    s.last_stop_speed_rad_s = std::abs(omega_rad_s);
  } else if (theta_rad > a.closed_stop_rad + a.stop_rearm_rad) {
    closed_armed_ = true;
  }
  s.time_s = time_s;
  s.theta_rad = theta_rad;
  s.omega_rad_s = omega_rad_s;
  ++s.ticks;
  store(s);
}

void DoorSnapshotChannel::store(const DoorSnapshot& snapshot) noexcept {
  std::uint64_t words[kWords] = {};
  std::memcpy(words, &snapshot, sizeof(DoorSnapshot));
  const std::uint64_t sequence = sequence_.load(std::memory_order_relaxed);
  sequence_.store(sequence + 1, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
  for (std::size_t i = 0; i < kWords; ++i) words_[i].store(words[i], std::memory_order_relaxed);
  sequence_.store(sequence + 2, std::memory_order_release);
}

DoorSnapshot DoorSnapshotChannel::read() const noexcept {
  std::uint64_t words[kWords];
  for (;;) {
    const std::uint64_t before = sequence_.load(std::memory_order_acquire);
    if ((before & 1U) != 0) {
      std::this_thread::yield();  // the writer is mid-publish (or was preempted there)
      continue;
    }
    for (std::size_t i = 0; i < kWords; ++i) words[i] = words_[i].load(std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_acquire);
    if (sequence_.load(std::memory_order_relaxed) == before) break;
  }
  DoorSnapshot snapshot;
  std::memcpy(&snapshot, words, sizeof(DoorSnapshot));
  return snapshot;
}

}  // namespace doorbench::haptic
