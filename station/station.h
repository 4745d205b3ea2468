#pragma once
// The live station (docs/station.md): a thread of its own that opens the StationWindow and,
// at the display's rate, draws the door at the newest tick's angle (read from the render
// loop's DoorSnapshotChannel, which never makes the tick wait), shows the question asked and
// hands back the participant's answer.
//
// Thread safety: start(), stop(), ask(), take_answer(), inject() and report() from any one
// control thread (they lock a mutex the station's thread takes once per frame, never the
// tick). The snapshot channel and the scene must outlive the Station.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "haptic/door_snapshot.h"
#include "station/station_window.h"

namespace doorbench::station {

struct StationReport {
  std::uint64_t frames = 0;
  double frame_interval_mean_ms = 0.0;  // between the starts of successive frames
  double frame_interval_max_ms = 0.0;
  StereoMode stereo = StereoMode::kMono;
  std::string note;   // e.g. why stereo fell back to mono
  std::string error;  // what ended the station's thread early, or ""
  std::string brief_report() const;
};

class Station {
 public:
  Station(const Scene& scene, const haptic::DoorSnapshotChannel& snapshot,
          StationWindowOptions options);
  ~Station();  // stops
  Station(const Station&) = delete;
  Station& operator=(const Station&) = delete;

  // Opens the window on the station's thread and returns once it is open; throws
  // std::runtime_error with the reason when it cannot be (no display, no such display).
  void start();
  void stop();

  // The question to show from the next frame (replacing any); throws std::invalid_argument
  // when it is not valid (Question::validate).
  void ask(const Question& question);
  // The answer given since the last call, if any (the question is then gone).
  std::optional<Answer> take_answer();
  // An input as the window's callbacks would deliver it (scripted input).
  void inject(const InputEvent& event);

  StationReport report() const;

 private:
  void run() noexcept;
  void frame_pacing(double& next_frame_s) const;

  const Scene& scene_;
  const haptic::DoorSnapshotChannel& snapshot_;
  StationWindowOptions options_;
  std::thread thread_;
  std::atomic<bool> quit_{false};
  mutable std::mutex mutex_;
  std::condition_variable opened_;
  bool open_done_ = false;
  std::string open_error_;
  // Under mutex_: the control side's requests and the station's results.
  std::optional<Question> asked_;
  std::vector<InputEvent> injected_;
  std::optional<Answer> answer_;
  StationReport report_;
  double refresh_hz_ = 60.0;
};

}  // namespace doorbench::station
