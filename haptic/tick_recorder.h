#pragma once
// Streams the render loop's ticks into a session file, in the same format as bench
// recordings (docs/session-format.md), so that analysis treats the haptic device as a
// measuring instrument exactly like the bench: the user's force along the handle's arc
// ("force", N), the door angle ("angle", rad) and rate ("rate", rad/s) are the channels a fit
// reads; every other quantity of the tick is a channel too (device position, velocity,
// measured and commanded force, model torque and its terms, passivity damping, constraint
// errors, safety scale, parameter-set id). Every channel has the tick times as explicit times
// (the ticks' real times, jitter included). Safety events become "safety" events, parameter
// changes "parameters" events naming the set; each set's parameter and effects files are
// kept in the group haptic/parameter_sets, the playback set-up in the group "haptic"
// (including handle_radius_m, which export reads as the recording's handle radius).
//
// The recorder is the ring's consumer: drain() on a writer thread (start()/stop()) or, when
// the loop runs in simulated time on one thread, called by that thread between ticks.
//
// Thread safety: drain() and close() from one thread at a time; note_parameter_set() and
// add_event() from any thread (they take the recorder's own lock, never held by the tick).
#include <atomic>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "acquisition/session/session_file.h"
#include "haptic/render_loop.h"

namespace doorbench::haptic {

struct PlaybackSetup {
  std::string device_name;
  std::string model_source;  // e.g. the --params path, or "reference door"
  std::string effects;       // as given, or ""
};

class TickRecorder {
 public:
  // Creates the session (an existing file is an error) with one channel per tick quantity;
  // term channels are named after the loop's first parameter set's terms.
  TickRecorder(const std::filesystem::path& path, const SessionMetadata& metadata, RenderLoop& loop,
               const DoorModel& model, const PlaybackSetup& setup);
  ~TickRecorder();
  TickRecorder(const TickRecorder&) = delete;
  TickRecorder& operator=(const TickRecorder&) = delete;

  // Keeps a parameter set's files (and description) for the session, by id.
  void note_parameter_set(int id, const std::string& description, const DoorModel& model);
  // An event from the control side (a tuning key, an A/B answer, a mark).
  void add_event(const SessionEvent& event);

  // Writes every tick record available now; returns how many.
  std::size_t drain();
  // A writer thread that drains every `interval_s` until stop().
  void start(double interval_s = 0.02);
  void stop();
  // Stops the thread, drains what is left, writes the groups and closes the file.
  void close();

  std::uint64_t ticks_written() const { return ticks_written_.load(std::memory_order_relaxed); }
  // The first trip's session event (SafetyLayer::describe(); a lost link with the device's
  // stop_reason()), or "" while none came. After close(), or from the thread that drains.
  const std::string& first_trip() const { return first_trip_; }
  const std::filesystem::path& path() const { return path_; }

 private:
  void flush_buffers();
  // The record's safety events, each described with its figure (SafetyLayer::describe()).
  void add_safety_events(const TickRecord& record, std::vector<SessionEvent>& events);

  std::filesystem::path path_;
  RenderLoop& loop_;
  PlaybackSetup setup_;
  std::unique_ptr<SessionWriter> writer_;
  struct Channel {
    int index;
    std::vector<double> values;
  };
  std::vector<Channel> channels_;
  std::vector<double> times_;
  int term_count_ = 0;
  int last_parameter_set_ = 0;
  // The facts of the previous record, for the figures of the next one's events.
  double previous_time_s_ = kNaN;
  std::uint64_t previous_sequence_ = 0;
  int stale_ticks_ = 0;
  std::string first_trip_;
  std::mutex mutex_;  // guards pending_events_, sets_ and the writer between threads
  std::vector<SessionEvent> pending_events_;
  struct KeptSet {
    int id;
    std::string description, parameters_json, effects_json;
  };
  std::vector<KeptSet> sets_;
  std::thread thread_;
  std::atomic<bool> running_{false};
  std::atomic<std::uint64_t> ticks_written_{0};
  bool closed_ = false;
};

}  // namespace doorbench::haptic
