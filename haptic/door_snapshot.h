#pragma once
// The newest tick's door state for readers outside the real-time loop (the participant's
// station draws and sounds the door from it): angle, speed, and counters of the events a
// sound follows (the latch released and caught, the end stops hit), published by the tick
// without allocating, locking or doing I/O, read by any number of threads without ever
// making the tick wait.
//
// A seqlock over a small trivially-copyable struct: the one writer (the tick) makes the
// sequence odd, stores the words, makes it even; a reader copies the words and retries when
// the sequence moved or was odd. The writer never waits; a reader retries only while a
// publish is under way (a few nanoseconds). Every word is a relaxed atomic, so there is no
// data race in the C++ sense.
//
// The events are counted by the publisher from each tick's angle, so that none is missed
// however rarely a reader looks: a reader compares the counters with those it saw last.
//
// Thread safety: publish() from one thread at a time (the tick's); read() from any thread.
#include <atomic>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>

#include "analysis/model/door_model.h"

namespace doorbench::haptic {

struct DoorSnapshot {
  double time_s = 0.0;  // the tick's time on the loop's clock
  double theta_rad = 0.0;
  double omega_rad_s = 0.0;
  double last_latch_event_time_s = -1.0;  // the newest unlatching or latching tick; −1: none
  double last_stop_speed_rad_s = 0.0;     // |ω| at the newest end-stop hit
  std::uint64_t ticks = 0;                // publishes so far
  std::uint32_t unlatches = 0;            // θ rose through the latch angle
  std::uint32_t latches = 0;              // θ fell back through it
  std::uint32_t open_stop_hits = 0;       // θ reached the open stop moving outwards
  std::uint32_t closed_stop_hits = 0;     // θ reached the closed stop moving inwards
};
static_assert(std::is_trivially_copyable_v<DoorSnapshot>);

// Where the events are: the latch angle (NaN: no latch events), the stops, and how the
// crossings are debounced.
struct DoorEventAngles {
  double latch_rad = 0.03;
  double closed_stop_rad = 0.0;
  double open_stop_rad = 1.57;
  double hysteresis_rad = 0.003;       // a crossing re-arms this far back on the other side
  double stop_zone_rad = 0.004;        // a stop is hit within this of it...
  double stop_rearm_rad = 0.03;        // ...and re-armed once the door is this far away again
  double min_stop_speed_rad_s = 0.05;  // slower arrivals are not a knock
  std::string validate() const;        // "" or one line naming the field

  // The model's latch angle (the sensory model's θ1, the physical model's catch depth over
  // its radius h / r_l; NaN for a model without a latch), its open stop at θ_max and its
  // closed stop at 0.
  static DoorEventAngles for_model(const DoorModel& model);
};

class DoorSnapshotChannel {
 public:
  explicit DoorSnapshotChannel(const DoorEventAngles& angles = {});  // throws invalid_argument
  const DoorEventAngles& angles() const { return angles_; }

  // The writer (one thread): counts the events this tick's angle makes and publishes.
  void publish(double time_s, double theta_rad, double omega_rad_s) noexcept;
  // Any thread: a consistent copy of the newest publish.
  DoorSnapshot read() const noexcept;

 private:
  static constexpr std::size_t kWords = (sizeof(DoorSnapshot) + 7) / 8;
  void store(const DoorSnapshot& snapshot) noexcept;

  DoorEventAngles angles_;
  // The writer's own state (only the tick touches it).
  DoorSnapshot current_{};
  bool latched_ = true, first_ = true, open_armed_ = true, closed_armed_ = true;
  // What readers see.
  std::atomic<std::uint64_t> sequence_{0};
  std::atomic<std::uint64_t> words_[kWords]{};
};

}  // namespace doorbench::haptic
