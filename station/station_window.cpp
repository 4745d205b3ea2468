#include "station/station_window.h"

#define GLFW_INCLUDE_NONE
#include <GL/gl.h>
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>

#include <algorithm>
#include <cctype>
#include <stdexcept>

#include "core/number_format.h"
#include "station/door_renderer.h"
#include "viewer/window.h"

namespace doorbench::station {
namespace {

std::string station_glfw_error;

void on_station_glfw_error(int code, const char* description) {
  station_glfw_error = std::string(description ? description : "")
                           .append(" (GLFW error ")
                           .append(std::to_string(code))
                           .append(")");
}

void start_glfw() {
  glfwSetErrorCallback(on_station_glfw_error);
  if (!glfwInit()) {
    throw std::runtime_error("station: cannot start GLFW: " + station_glfw_error +
                             " (is DISPLAY set? headless: run under xvfb-run -a)");
  }
}

std::vector<std::string> displays_of_started_glfw() {
  int count = 0;
  GLFWmonitor** monitors = glfwGetMonitors(&count);
  std::vector<std::string> lines;
  for (int i = 0; i < count; ++i) {
    const GLFWvidmode* mode = glfwGetVideoMode(monitors[i]);
    std::string line = std::to_string(i) + " '" + glfwGetMonitorName(monitors[i]) + "'";
    if (mode != nullptr) {
      // Appended piece by piece (GCC 12's -Wrestrict misreads "..." + std::string&&).
      line.append(" ").append(std::to_string(mode->width)).append("x");
      line.append(std::to_string(mode->height));
      if (mode->refreshRate > 0)
        line.append("@").append(std::to_string(mode->refreshRate)).append(" Hz");
    }
    lines.push_back(line);
  }
  return lines;
}

// The display named by --station-display: an index into GLFW's list or a name; "" the
// primary (which may be none).
GLFWmonitor* choose_display(const std::string& display) {
  int count = 0;
  GLFWmonitor** monitors = glfwGetMonitors(&count);
  if (display.empty()) return glfwGetPrimaryMonitor();
  const bool digits = std::all_of(display.begin(), display.end(),
                                  [](unsigned char c) { return std::isdigit(c) != 0; });
  if (digits && display.size() < 4 && std::stoi(display) < count) {
    return monitors[std::stoi(display)];
  }
  for (int i = 0; i < count; ++i) {
    if (display == glfwGetMonitorName(monitors[i])) return monitors[i];
  }
  std::string there;
  for (const std::string& line : displays_of_started_glfw()) {
    there += (there.empty() ? "" : ", ") + line;
  }
  throw std::runtime_error("--station-display '" + display + "': no such display (displays: " +
                           (there.empty() ? std::string("none") : there) + ")");
}

}  // namespace

std::string StationWindowOptions::validate() const {
  if (width_px < 64 || width_px > 16384) return "width_px must be 64..16384";
  if (height_px < 64 || height_px > 16384) return "height_px must be 64..16384";
  if (!(max_frame_rate_hz == 0.0 || (max_frame_rate_hz >= 1.0 && max_frame_rate_hz <= 1000.0))) {
    return "the frame rate must be 1 to 1000 Hz (0: the display's)";
  }
  if (nice < 0 || nice > 19) return "the nice value must be 0 to 19";
  return "";
}

std::vector<std::string> list_displays() {
  start_glfw();
  std::vector<std::string> lines = displays_of_started_glfw();
  glfwTerminate();
  return lines;
}

struct StationWindow::Impl {
  GLFWwindow* window = nullptr;
  std::vector<InputEvent> pending;
  bool imgui = false;

  static void on_key(GLFWwindow* window, int key, int, int action, int) {
    if (action != GLFW_PRESS) return;
    auto* self = static_cast<Impl*>(glfwGetWindowUserPointer(window));
    self->pending.push_back({InputEvent::Kind::kKey, key, 0.0, 0.0});
  }
  static void on_character(GLFWwindow* window, unsigned int codepoint) {
    auto* self = static_cast<Impl*>(glfwGetWindowUserPointer(window));
    self->pending.push_back({InputEvent::Kind::kCharacter, int(codepoint), 0.0, 0.0});
  }
  static void on_button(GLFWwindow* window, int button, int action, int) {
    if (button != GLFW_MOUSE_BUTTON_LEFT || action != GLFW_PRESS) return;
    auto* self = static_cast<Impl*>(glfwGetWindowUserPointer(window));
    double x = 0.0, y = 0.0;
    glfwGetCursorPos(window, &x, &y);
    self->pending.push_back({InputEvent::Kind::kClick, 0, x, y});
  }
};

StationWindow::StationWindow(const Scene& scene, const StationWindowOptions& options)
    : impl_(std::make_unique<Impl>()), scene_(scene) {
  if (std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument("station window: " + problem);
  }
  start_glfw();
  try {
    GLFWmonitor* monitor = choose_display(options.display);
    if (monitor == nullptr && !options.display.empty()) monitor = glfwGetPrimaryMonitor();
    const GLFWvidmode* mode = monitor ? glfwGetVideoMode(monitor) : nullptr;
    if (mode != nullptr && mode->refreshRate > 0) refresh_hz_ = mode->refreshRate;
    const bool fullscreen = options.fullscreen && options.visible && mode != nullptr;
    if (options.fullscreen && options.visible && mode == nullptr) {
      note_ = "no display to fill: a window instead";
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 0);
    glfwWindowHint(GLFW_VISIBLE, options.visible ? GLFW_TRUE : GLFW_FALSE);
    glfwWindowHint(GLFW_DEPTH_BITS, 24);
    if (fullscreen) glfwWindowHint(GLFW_REFRESH_RATE, mode->refreshRate);
    const int width = fullscreen ? mode->width : options.width_px;
    const int height = fullscreen ? mode->height : options.height_px;
    GLFWmonitor* on = fullscreen ? monitor : nullptr;
    stereo_ = scene.stereo.mode;
    if (stereo_ == StereoMode::kQuadBuffer) {
      glfwWindowHint(GLFW_STEREO, GLFW_TRUE);
      impl_->window = glfwCreateWindow(width, height, "doorbench station", on, nullptr);
      if (impl_->window == nullptr) {
        note_ = "quad-buffer stereo is not offered by this display (" + station_glfw_error +
                "): drawing mono";
        stereo_ = StereoMode::kMono;
        glfwWindowHint(GLFW_STEREO, GLFW_FALSE);
      }
    }
    if (impl_->window == nullptr) {
      impl_->window = glfwCreateWindow(width, height, "doorbench station", on, nullptr);
    }
    if (impl_->window == nullptr) {
      throw std::runtime_error("station: cannot open an OpenGL window: " + station_glfw_error);
    }
  } catch (...) {
    glfwTerminate();
    throw;
  }
  glfwMakeContextCurrent(impl_->window);
  glfwSwapInterval(1);  // at the display's rate
  glfwSetWindowUserPointer(impl_->window, impl_.get());
  glfwSetKeyCallback(impl_->window, Impl::on_key);
  glfwSetMouseButtonCallback(impl_->window, Impl::on_button);
  glfwSetCharCallback(impl_->window, Impl::on_character);
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;
  ImGui::StyleColorsDark();
  ImGui_ImplGlfw_InitForOpenGL(impl_->window, false);
  ImGui_ImplOpenGL3_Init("#version 130");
  impl_->imgui = true;
}

StationWindow::~StationWindow() {
  if (impl_->imgui) {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  glfwDestroyWindow(impl_->window);
  glfwTerminate();
}

int StationWindow::width_px() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(impl_->window, &w, &h);
  return w;
}
int StationWindow::height_px() const {
  int w = 0, h = 0;
  glfwGetFramebufferSize(impl_->window, &w, &h);
  return h;
}

namespace {

void draw_panel(const QuestionPanel& panel, double width, double height) {
  const Question& q = panel.question();
  const PanelRect box = panel.panel_rect(width, height);
  ImGui::SetNextWindowPos(ImVec2(float(box.x), float(box.y)));
  ImGui::SetNextWindowSize(ImVec2(float(box.width), float(box.height)));
  ImGui::Begin("question", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoFocusOnAppearing);
  ImGui::SetWindowFontScale(float(std::max(1.0, height / 400.0)));
  ImGui::TextUnformatted(q.prompt.c_str());
  for (const std::string& line : q.key_help) ImGui::TextUnformatted(line.c_str());
  const std::vector<PanelRect> rects = panel.choice_rects(width, height);
  for (std::size_t i = 0; i < rects.size(); ++i) {
    ImGui::SetCursorScreenPos(ImVec2(float(rects[i].x), float(rects[i].y)));
    // The key that picks it, unless the choice is that number already (a scale's points).
    const std::string number = std::to_string(i + 1);
    const std::string label = q.choices[i] == number ? number : number + ": " + q.choices[i];
    ImGui::Button(label.c_str(), ImVec2(float(rects[i].width), float(rects[i].height)));
  }
  if (!rects.empty()) {
    const float below = float(rects[0].y + rects[0].height + 4.0);
    ImGui::SetCursorScreenPos(ImVec2(float(rects.front().x), below));
    ImGui::TextUnformatted(q.low_anchor.c_str());
    const float w = ImGui::CalcTextSize(q.high_anchor.c_str()).x;
    ImGui::SetCursorScreenPos(ImVec2(float(rects.back().x + rects.back().width) - w, below));
    ImGui::TextUnformatted(q.high_anchor.c_str());
  }
  ImGui::End();
}

// The caption across the top of the window: its title, then its lines.
void draw_caption(const Caption& caption, double width, double height) {
  ImGui::SetNextWindowPos(ImVec2(float(0.05 * width), float(0.03 * height)));
  ImGui::SetNextWindowSize(ImVec2(float(0.9 * width), 0.0f));
  ImGui::Begin("caption", nullptr,
               ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoMove |
                   ImGuiWindowFlags_NoSavedSettings | ImGuiWindowFlags_NoFocusOnAppearing |
                   ImGuiWindowFlags_AlwaysAutoResize);
  ImGui::SetWindowFontScale(float(std::max(1.0, height / 400.0)));
  ImGui::TextUnformatted(caption.title.c_str());
  for (const std::string& line : caption.lines) ImGui::TextUnformatted(line.c_str());
  ImGui::End();
}

}  // namespace

void StationWindow::draw(double theta_rad, const QuestionPanel& panel, const Caption& caption) {
  draw(scene_, theta_rad, panel, caption);
}

void StationWindow::draw(const Scene& scene, double theta_rad, const QuestionPanel& panel,
                         const Caption& caption) {
  int w = 0, h = 0;
  glfwGetFramebufferSize(impl_->window, &w, &h);
  w = std::max(w, 2);
  h = std::max(h, 2);
  switch (stereo_) {
    case StereoMode::kMono:
      draw_scene(scene, theta_rad, Eye::kCentre, {0, 0, w, h});
      break;
    case StereoMode::kQuadBuffer:
      glDrawBuffer(GL_BACK_LEFT);
      draw_scene(scene, theta_rad, Eye::kLeft, {0, 0, w, h});
      glDrawBuffer(GL_BACK_RIGHT);
      draw_scene(scene, theta_rad, Eye::kRight, {0, 0, w, h});
      glDrawBuffer(GL_BACK);
      break;
    case StereoMode::kSideBySide:
      draw_scene(scene, theta_rad, Eye::kLeft, {0, 0, w / 2, h});
      draw_scene(scene, theta_rad, Eye::kRight, {w / 2, 0, w - w / 2, h});
      break;
    case StereoMode::kTopBottom:
      draw_scene(scene, theta_rad, Eye::kLeft, {0, h - h / 2, w, h / 2});
      draw_scene(scene, theta_rad, Eye::kRight, {0, 0, w, h - h / 2});
      break;
  }
  glViewport(0, 0, w, h);
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  ImGui::NewFrame();
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  if (!caption.empty()) draw_caption(caption, size.x, size.y);
  if (panel.asking()) draw_panel(panel, size.x, size.y);
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

void StationWindow::swap() {
  glfwSwapBuffers(impl_->window);
}

void StationWindow::poll(std::vector<InputEvent>& events) {
  glfwPollEvents();
  events.insert(events.end(), impl_->pending.begin(), impl_->pending.end());
  impl_->pending.clear();
}

bool StationWindow::close_requested() const {
  return glfwWindowShouldClose(impl_->window);
}

void StationWindow::write_png(const std::filesystem::path& png) const {
  const int w = width_px(), h = height_px();
  viewer::write_framebuffer_png(h, 0, 0, w, h, png);
}

StereoMode station_screenshot(const Scene& scene, double theta_rad,
                              const std::filesystem::path& png, StationWindowOptions options,
                              const Question* question, const Caption& caption) {
  options.fullscreen = false;
  options.visible = false;
  StationWindow window(scene, options);
  QuestionPanel panel;
  if (question != nullptr) panel.ask(*question);
  // ImGui places a window from the previous frame's sizes: two frames settle it.
  for (int i = 0; i < 3; ++i) {
    window.draw(theta_rad, panel, caption);
    if (i < 2) window.swap();
  }
  window.write_png(png);
  return window.stereo();
}

}  // namespace doorbench::station
