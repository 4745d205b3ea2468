#pragma once
// The door's sounds at the station (docs/station.md), through OpenAL Soft: the latch's click
// when the door unlatches and when it latches, the end stop's knock (louder the faster the
// door arrives) and the hinge's sound, looping, its gain following the door's speed. Each
// sample comes from the WAV file the scene names (any format libsndfile reads, mixed down
// to mono) or is synthesised by the program. The sources sit at the door in 3-D: the click
// at the handle, the knock and the hinge at the hinge; the listener at the scene's camera.
//
// A thread of its own polls the render loop's DoorSnapshotChannel every 2 ms and starts a
// sound when an event counter moved: the tick never waits, allocates or does I/O for sound.
// That thread asks for SCHED_FIFO at priority 20 (below the tick's 80) and runs best effort
// where that is not permitted (SoundReport::fifo).
//
// Thread safety: start(), stop() and report() from one control thread; the snapshot must
// outlive stop().
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "haptic/door_snapshot.h"
#include "station/scene.h"

namespace doorbench::station {

// A mono sample, 16-bit, at its rate.
struct SoundSample {
  std::vector<std::int16_t> frames;
  int rate_hz = 44100;
  double duration_s() const { return double(frames.size()) / rate_hz; }
};

// The built-in sounds (deterministic): a 20 ms click with a sharp onset, a 150 ms knock, a
// one-second hinge loop.
SoundSample synthesised_click();
SoundSample synthesised_knock();
SoundSample synthesised_hinge();
// A WAV (or any libsndfile format) mixed down to mono; throws SceneError naming the file.
SoundSample read_sound_file(const std::filesystem::path& file);

// A set of the door's sounds read and ready to play: the levels and the samples (the files
// named, the built-in sounds for those not named), and where they came from (`source`: a
// sound set's or scene file's path, "built-in").
struct SoundSamples {
  std::string source;
  Sounds sounds;
  SoundSample click, knock, hinge;
};
// Reads the samples of `sounds`; throws SceneError naming a file that cannot be read.
SoundSamples load_sound_samples(const Sounds& sounds, std::string source);

struct SoundReport {
  std::string sounds;                    // SoundSamples::source of what plays
  std::string device;                    // OpenAL's name for the output
  std::uint64_t clicks = 0, knocks = 0;  // sounds started
  double latency_ms = -1.0;              // the device's reported output latency; −1 unknown
  bool fifo = false;                     // the polling thread got SCHED_FIFO (priority 20)
  std::string error;                     // why there is no sound, or ""
  std::string brief_report() const;
};

class DoorSound {
 public:
  // Loads the samples (the scene's files or the built-in ones); throws SceneError naming a
  // file that cannot be read.
  DoorSound(const Scene& scene, const haptic::DoorSnapshotChannel& snapshot);
  // The scene's geometry (where the sources and the listener are) with `samples` (copied).
  DoorSound(const Scene& scene, const SoundSamples& samples,
            const haptic::DoorSnapshotChannel& snapshot);
  ~DoorSound();
  DoorSound(const DoorSound&) = delete;
  DoorSound& operator=(const DoorSound&) = delete;

  // Opens the default output and starts the polling thread. Throws std::runtime_error with
  // OpenAL's reason when no output can be opened.
  void start();
  void stop();
  SoundReport report() const;
  // The monotonic_now_s() of the output's first frame: the earliest, over every poll, of the
  // time less the output's device clock (ALC_SOFT_device_clock: the frames mixed so far), so
  // that a frame's index in a recording of the output tells when it was due. Without that
  // extension, the time the output was opened. Any thread, after start().
  double mixing_started_at_s() const {
    return mixing_started_at_s_.load(std::memory_order_acquire);
  }

 private:
  struct Al;
  void run() noexcept;
  void place_sources(double theta_rad);
  void note_device_clock();

  const Scene& scene_;
  const haptic::DoorSnapshotChannel& snapshot_;
  Sounds sounds_;
  SoundSample click_, knock_, hinge_;
  std::unique_ptr<Al> al_;
  std::thread thread_;
  std::atomic<bool> quit_{false};
  std::atomic<std::uint64_t> clicks_{0}, knocks_{0};
  std::atomic<double> mixing_started_at_s_{0.0};
  SoundReport report_;
};

}  // namespace doorbench::station
