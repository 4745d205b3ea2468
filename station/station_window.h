#pragma once
// The participant's station window (docs/station.md): GLFW + OpenGL, full screen on the
// display the participant faces (or a window of a given size), drawing the scene's door at
// an angle, in stereo where asked and offered, with the question panel over it.
//
// A StationWindow is used from one thread only, the one that made it (GLFW's and OpenGL's
// rule for a context; on X11 that thread need not be the process's first).
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "station/question_panel.h"
#include "station/scene.h"

namespace doorbench::station {

struct StationWindowOptions {
  std::string display;     // "" the primary display; else a display's name or index
  bool fullscreen = true;  // false: a window of width_px x height_px
  bool visible = true;     // false: a hidden window (screenshots)
  int width_px = 1280, height_px = 800;
  // The live station's frames at most this often (0: the display's rate).
  double max_frame_rate_hz = 0.0;
  // The live station's drawing thread runs at this nice value (0 to 19), and so do the
  // threads its OpenGL starts (Mesa's llvmpipe renders on threads of its own, which inherit
  // it): above 0, drawing yields the cores to the playback's non-real-time threads, and to
  // any other busy process (docs/PERFORMANCE.md: under load it then draws a few frames a
  // second).
  int nice = 0;
  std::string validate() const;  // "" or one line naming the option
};

// The displays GLFW sees, as "INDEX 'NAME' WIDTHxHEIGHT@RATE Hz" lines; throws
// std::runtime_error when GLFW cannot start (no X display).
std::vector<std::string> list_displays();

class StationWindow {
 public:
  // Opens the window. Throws std::runtime_error naming the reason (no display, no OpenGL,
  // --station-display naming no display: the message lists those there are).
  StationWindow(const Scene& scene, const StationWindowOptions& options);
  ~StationWindow();
  StationWindow(const StationWindow&) = delete;
  StationWindow& operator=(const StationWindow&) = delete;

  // One frame of the door at theta_rad (with `caption` at the top, and `panel` over it when
  // it asks) into the back buffer; swap() shows it.
  void draw(double theta_rad, const QuestionPanel& panel, const Caption& caption = {});
  // The same with another scene than the window's (its stereo mode stays the window's).
  void draw(const Scene& scene, double theta_rad, const QuestionPanel& panel,
            const Caption& caption = {});
  void swap();
  // Pending window events; the keys, clicks and typed characters among them are appended
  // to `events`.
  void poll(std::vector<InputEvent>& events);
  bool close_requested() const;
  // The back buffer as an RGB PNG (after draw(), before swap()).
  void write_png(const std::filesystem::path& png) const;

  StereoMode stereo() const { return stereo_; }      // what is drawn (mono when not offered)
  const std::string& note() const { return note_; }  // e.g. why stereo fell back to mono
  double refresh_hz() const { return refresh_hz_; }
  int width_px() const;
  int height_px() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  const Scene& scene_;
  StereoMode stereo_ = StereoMode::kMono;
  std::string note_;
  double refresh_hz_ = 60.0;
};

// The door at theta_rad in a hidden window of the options' size, written to `png` (RGB);
// returns the stereo mode drawn (the scene's, or mono where quad-buffer is not offered).
StereoMode station_screenshot(const Scene& scene, double theta_rad,
                              const std::filesystem::path& png, StationWindowOptions options,
                              const Question* question = nullptr, const Caption& caption = {});

}  // namespace doorbench::station
