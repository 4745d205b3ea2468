#pragma once
// Parameter sets for playback and their lock-free hand-off to the render loop's tick.
//
// A PlaybackParameters is one validated, immutable parameter set: the door model (any fitted
// model plus effects), the inertia the device renders for it, which of its terms are active
// (inject energy: the sensory model's snap), an id and a description for the session.
//
// ParameterMailbox: the control side (command line, viewer, tuning keys, A/B) publishes a new
// set at any time; the tick takes the newest at its next tick boundary, so a set is applied
// whole and never half-way through a tick. The tick's side is wait-free: one atomic exchange,
// no lock, no allocation, no free. Sets the tick no longer uses are freed on the control side
// (publish() and reclaim()), never in the tick.
//
// Thread safety: publish(), reclaim() and description() from one control thread (or under the
// caller's own lock); take() and in_use() from the tick thread only.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "analysis/model/door_model.h"
#include "core/clock.h"
#include "haptic/door_mapping.h"

namespace doorbench::haptic {

// The model as it is played: without the force-offset effect, which describes the bench's
// load cell, not the door (door-models.md §4); every other effect is kept.
DoorModel playable_model(const DoorModel& model);

struct PlaybackParameters {
  PlaybackParameters(const DoorModel& door_model, const DoorMapping& mapping, std::string what);

  DoorModel model;
  double device_inertia = 0.0;    // what the device renders: mapping.inertia_on_device(J)
  std::vector<int> active_terms;  // indices of the model's terms that inject energy
  std::string description;        // e.g. "start: fitted params FIT.json", "key +: heaviness 1.05"
  int id = 0;                     // set by the mailbox: 1, 2, ... in publishing order
  // CLOCK_MONOTONIC (s) when published, for the change-to-first-tick latency.
  double published_time_s = 0.0;
};

class ParameterMailbox {
 public:
  ParameterMailbox() = default;
  ~ParameterMailbox();
  ParameterMailbox(const ParameterMailbox&) = delete;
  ParameterMailbox& operator=(const ParameterMailbox&) = delete;

  // Control side: gives the set its id and hands it over; a set published earlier that the
  // tick never took is dropped (the newest wins). Returns the id.
  int publish(std::unique_ptr<PlaybackParameters> parameters);
  // Control side: CLOCK_MONOTONIC (s) of the last publish().
  double last_published_time_s() const { return last_published_time_s_; }
  // Control side: the id the next publish() will give.
  int next_id() const { return next_id_; }
  // Control side: frees the sets older than the one the tick uses. Returns how many are kept.
  std::size_t reclaim();
  // Control side: the description of a set by id ("" if unknown or freed).
  std::string description(int id) const;

  // Tick: the newest set published since the last call, or nullptr. After it returns a set,
  // the tick must not use the set it had before.
  const PlaybackParameters* take() noexcept;
  // The id of the set the tick uses (0 before the first take()).
  int in_use() const noexcept { return in_use_id_.load(std::memory_order_acquire); }
  // Tick: CLOCK_MONOTONIC (s) when the tick took the set it uses now.
  double taken_time_s() const noexcept { return taken_time_s_.load(std::memory_order_acquire); }

 private:
  std::atomic<PlaybackParameters*> pending_{nullptr};
  std::atomic<int> in_use_id_{0};
  std::atomic<double> taken_time_s_{0.0};
  // Control side only: every set not yet freed, in id order.
  std::vector<std::unique_ptr<PlaybackParameters>> kept_;
  int next_id_ = 1;
  double last_published_time_s_ = 0.0;
};

}  // namespace doorbench::haptic
