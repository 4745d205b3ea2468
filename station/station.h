#pragma once
// The live station (docs/station.md): a thread of its own that opens the StationWindow and,
// at the display's rate, draws the door at the newest tick's angle (read from the render
// loop's DoorSnapshotChannel, which never makes the tick wait), shows the question asked and
// hands back the participant's answer.
//
// Between playbacks (a trial's question, the next trial) the station follows no snapshot and
// the door rests closed; follow() switches it to a playback's snapshot and back.
//
// Thread safety: start(), stop(), follow(), show(), show_scene(), capture(), ask(),
// take_answer(), take_typed(), inject(), pick(), window_size(), running() and report() from
// any one control thread (they lock a mutex the station's thread takes once per frame, never
// the tick). The scene must outlive the Station, a followed snapshot channel the
// follow(nullptr) (or stop()) after it.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "haptic/door_snapshot.h"
#include "station/station_window.h"

namespace doorbench::station {

struct StationReport {
  std::uint64_t frames = 0;
  double frame_interval_mean_ms = 0.0;  // between the starts of successive frames
  double frame_interval_max_ms = 0.0;
  StereoMode stereo = StereoMode::kMono;
  std::string note;     // e.g. why stereo fell back to mono
  std::string error;    // what ended the station's thread early, or ""
  bool closed = false;  // the window was closed (by its close button or the window manager)
  std::string scene;    // Scene::source of the scene the latest frame drew
  std::uint64_t scene_changes = 0;  // frames that drew another scene than the frame before
  std::string brief_report() const;
};

class Station {
 public:
  Station(const Scene& scene, const haptic::DoorSnapshotChannel& snapshot,
          StationWindowOptions options);
  // A station that follows no playback yet (follow()).
  Station(const Scene& scene, StationWindowOptions options);
  ~Station();  // stops
  Station(const Station&) = delete;
  Station& operator=(const Station&) = delete;

  // Opens the window on the station's thread and returns once it is open; throws
  // std::runtime_error with the reason when it cannot be (no display, no such display).
  void start();
  void stop();

  // The door drawn from the next frame: at `snapshot`'s angle, or closed (null). Once it
  // returns the station's thread no longer reads the channel followed before.
  void follow(const haptic::DoorSnapshotChannel* snapshot);
  // The caption over the door (e.g. "Presentation 1", a tuning's key help) from the next
  // frame; an empty one shows nothing.
  void show(const Caption& caption);
  // The scene drawn from the next frame (null: the station's own). It must outlive the
  // show_scene() that replaces it (or stop()). The window's stereo mode stays the one it
  // opened with (the station's scene's).
  void show_scene(const Scene* scene);
  // Writes the next frame drawn to `png` (RGB) and returns once it is written; throws
  // std::runtime_error when the station is not drawing or the frame does not come within
  // `timeout_s`.
  void capture(const std::filesystem::path& png, double timeout_s = 30.0);
  // The question to show from the next frame (replacing any); throws std::invalid_argument
  // when it is not valid (Question::validate).
  void ask(const Question& question);
  // The answer given since the last call, if any (the question is then gone).
  std::optional<Answer> take_answer();
  // An input as the window's callbacks would deliver it (scripted input).
  void inject(const InputEvent& event);
  // Scripted input as a participant gives it: the key of choice `choice` (1 to 9 on the main
  // row), or a click in the middle of its button in the window as it is now, of the question
  // last asked, through inject(). Throws std::invalid_argument for a choice it does not have.
  void pick(std::size_t choice, bool by_click);
  // The characters typed on the station since the last call ('\n' for Enter or the
  // keypad's Enter), as text input delivers them (shift and layout applied).
  std::string take_typed();
  // The window's size in pixels as of the latest frame (for clicks on choice_rects).
  std::pair<double, double> window_size() const;
  // Whether the station's thread is still drawing (false once its window was closed or it
  // stopped on an error: report().error says which).
  bool running() const;

  StationReport report() const;

 private:
  void run() noexcept;
  void write_capture(const StationWindow& window, const std::filesystem::path& png);
  void frame_pacing(double& next_frame_s) const;

  const Scene& scene_;
  StationWindowOptions options_;
  std::thread thread_;
  std::atomic<bool> quit_{false};
  mutable std::mutex mutex_;
  std::condition_variable opened_;
  bool open_done_ = false;
  std::string open_error_;
  // Under mutex_: the control side's requests and the station's results.
  const haptic::DoorSnapshotChannel* snapshot_ = nullptr;
  const Scene* shown_scene_ = nullptr;
  std::filesystem::path capture_png_;  // "" when no capture is asked for
  std::uint64_t captures_done_ = 0;
  std::string capture_error_;
  std::condition_variable captured_;
  Caption caption_;
  std::optional<Question> asked_;
  Question last_asked_;
  std::vector<InputEvent> injected_;
  std::string typed_;
  double width_px_ = 0.0, height_px_ = 0.0;
  bool running_ = false;
  std::optional<Answer> answer_;
  StationReport report_;
  double refresh_hz_ = 60.0;
};

}  // namespace doorbench::station
