#pragma once
// The viewer's window: GLFW + OpenGL 3 + Dear ImGui (the backends from Debian's
// libimgui-dev examples), interactive or headless for one screenshot.
#include <filesystem>
#include <string>

#include "viewer/viewer_app.h"

namespace doorbench::viewer {

struct WindowOptions {
  int width_px = 1400;
  int height_px = 900;
  std::string title = "doorbench view";
  std::string validate() const;  // "" or one line naming the option
};

// Opens the window and runs until it is closed. Throws std::runtime_error when no window
// can be opened (no display, no OpenGL 3), with GLFW's reason.
void run_window(Viewer& viewer, const WindowOptions& options);

// Renders `layout` in a hidden window of the given size (a few frames, so that ImGui's
// layout settles), reads the frame back with glReadPixels and writes it to `png` (RGB).
// Next to it, `png` + ".json" says where each plot's data area is and what ranges it shows.
void screenshot(Viewer& viewer, const std::string& layout, const std::filesystem::path& png,
                const WindowOptions& options);

// Reads the rectangle (x, y, w, h; framebuffer pixels, y downwards) of the current context's
// back buffer and writes it as an RGB PNG (the viewer's and the station's screenshots).
// Throws std::runtime_error naming the file when it cannot be written.
void write_framebuffer_png(int fb_height, int x, int y, int w, int h,
                           const std::filesystem::path& png);

}  // namespace doorbench::viewer
