#include "viewer/window.h"

#define GLFW_INCLUDE_NONE
#include <GL/gl.h>
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>
#include <stb_image_write.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <vector>

namespace doorbench::viewer {

namespace {

std::string glfw_error;

void on_glfw_error(int code, const char* description) {
  glfw_error = std::string(description ? description : "")
                   .append(" (GLFW error ")
                   .append(std::to_string(code))
                   .append(")");
}

// GLFW, a window with an OpenGL 3 context and ImGui on it; undone in reverse order.
class GlSession {
 public:
  GlSession(const WindowOptions& options, bool visible) {
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit()) {
      throw std::runtime_error(std::string("cannot start GLFW: ")
                                   .append(glfw_error)
                                   .append(" (is DISPLAY set? headless: run under xvfb-run -a)"));
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 0);
    glfwWindowHint(GLFW_VISIBLE, visible ? GLFW_TRUE : GLFW_FALSE);
    window_ = glfwCreateWindow(options.width_px, options.height_px, options.title.c_str(), nullptr,
                               nullptr);
    if (window_ == nullptr) {
      glfwTerminate();
      throw std::runtime_error(std::string("cannot open an OpenGL 3 window: ").append(glfw_error));
    }
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(1);
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini in the user's folder
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForOpenGL(window_, visible);
    ImGui_ImplOpenGL3_Init("#version 130");
  }
  ~GlSession() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
    glfwDestroyWindow(window_);
    glfwTerminate();
  }
  GlSession(const GlSession&) = delete;
  GlSession& operator=(const GlSession&) = delete;

  // One frame into the back buffer; returns the framebuffer's size.
  void render(Viewer& viewer, const std::string& layout, int& fb_width, int& fb_height) {
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    const ImVec2 size = ImGui::GetIO().DisplaySize;
    viewer.frame(size.x, size.y, layout);
    ImGui::Render();
    glfwGetFramebufferSize(window_, &fb_width, &fb_height);
    glViewport(0, 0, fb_width, fb_height);
    glClearColor(0.1f, 0.1f, 0.12f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  }
  GLFWwindow* window() const { return window_; }

 private:
  GLFWwindow* window_ = nullptr;
};

// A plot's PNG button: its widget's rectangle of the frame just rendered.
void fulfil_png_request(Viewer& viewer, int fb_width, int fb_height) {
  const auto request = viewer.take_png_request();
  if (!request) return;
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  const double sx = display.x > 0 ? fb_width / double(display.x) : 1.0;
  const double sy = display.y > 0 ? fb_height / double(display.y) : 1.0;
  const int x = std::clamp(int(std::lround(request->rect.x * sx)), 0, fb_width - 1);
  const int y = std::clamp(int(std::lround(request->rect.y * sy)), 0, fb_height - 1);
  const int w = std::clamp(int(std::lround(request->rect.width * sx)), 1, fb_width - x);
  const int h = std::clamp(int(std::lround(request->rect.height * sy)), 1, fb_height - y);
  try {
    write_framebuffer_png(fb_height, x, y, w, h, request->path);
    viewer.set_status("wrote " + request->path.string());
  } catch (const std::exception& error) {
    viewer.set_status(error.what());
  }
}

}  // namespace

void write_framebuffer_png(int fb_height, int x, int y, int w, int h,
                           const std::filesystem::path& png) {
  std::vector<unsigned char> pixels(std::size_t(w) * std::size_t(h) * 3);
  glFinish();
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadBuffer(GL_BACK);
  // OpenGL counts rows from the bottom.
  glReadPixels(x, fb_height - y - h, w, h, GL_RGB, GL_UNSIGNED_BYTE, pixels.data());
  if (const GLenum error = glGetError(); error != GL_NO_ERROR) {
    throw std::runtime_error("glReadPixels failed (GL error " + std::to_string(error) + ")");
  }
  // OpenGL's rows go bottom-up; PNG's top-down.
  const std::size_t row = std::size_t(w) * 3;
  std::vector<unsigned char> flipped(pixels.size());
  for (int r = 0; r < h; ++r) {
    std::copy_n(pixels.data() + std::size_t(h - 1 - r) * row, row,
                flipped.data() + std::size_t(r) * row);
  }
  if (stbi_write_png(png.string().c_str(), w, h, 3, flipped.data(), int(row)) == 0) {
    throw std::runtime_error(png.string() + ": cannot write the PNG");
  }
}

std::string WindowOptions::validate() const {
  if (width_px < 200 || width_px > 16384) return "width_px must be 200..16384";
  if (height_px < 150 || height_px > 16384) return "height_px must be 150..16384";
  return "";
}

void run_window(Viewer& viewer, const WindowOptions& options) {
  const std::string problem = options.validate();
  if (!problem.empty()) throw std::invalid_argument("window: " + problem);
  GlSession session(options, true);
  while (!glfwWindowShouldClose(session.window())) {
    glfwPollEvents();
    int w = 0, h = 0;
    session.render(viewer, "", w, h);
    fulfil_png_request(viewer, w, h);
    glfwSwapBuffers(session.window());
  }
}

void screenshot(Viewer& viewer, const std::string& layout, const std::filesystem::path& png,
                const WindowOptions& options) {
  const std::string problem = options.validate();
  if (!problem.empty()) throw std::invalid_argument("screenshot: " + problem);
  const std::string layout_problem = check_layout(layout);
  if (!layout_problem.empty()) throw std::invalid_argument("screenshot: " + layout_problem);
  GlSession session(options, false);
  int w = 0, h = 0;
  // ImGui sizes some items from the previous frame: let it settle.
  for (int i = 0; i < 3; ++i) {
    session.render(viewer, layout, w, h);
    if (i < 2) glfwSwapBuffers(session.window());
  }
  write_framebuffer_png(h, 0, 0, w, h, png);
  // Where each plot is, in the PNG's pixels (the framebuffer may be scaled on HiDPI).
  const ImVec2 display = ImGui::GetIO().DisplaySize;
  const double sx = display.x > 0 ? w / double(display.x) : 1.0;
  const double sy = display.y > 0 ? h / double(display.y) : 1.0;
  nlohmann::ordered_json info;
  info["width_px"] = w;
  info["height_px"] = h;
  info["layout"] = layout;
  info["plots"] = nlohmann::ordered_json::array();
  for (const PlotRecord& p : viewer.plots()) {
    nlohmann::ordered_json plot;
    plot["title"] = p.title;
    plot["area_px"] = {p.area.x * sx, p.area.y * sy, p.area.width * sx, p.area.height * sy};
    plot["x_range"] = {p.x.min, p.x.max};
    plot["y_range"] = {p.y.min, p.y.max};
    plot["labels"] = p.labels;
    plot["series"] = nlohmann::ordered_json::array();
    for (std::size_t i = 0; i < p.series.size(); ++i) {
      const Rgba c = p.colours[i];
      plot["series"].push_back({{"name", p.series[i]}, {"rgb", {c.r, c.g, c.b}}});
    }
    info["plots"].push_back(plot);
  }
  std::ofstream out(png.string() + ".json");
  out << info.dump(2) << "\n";
  if (!out) throw std::runtime_error(png.string() + ".json: cannot write");
}

}  // namespace doorbench::viewer
