#pragma once
// Helpers for tests of the viewer: a one-channel session to show; run `doorbench view
// --screenshot` under Xvfb (xvfb-run, Mesa's software OpenGL), load the PNG (stb_image,
// libstb) and its companion PNG.json (where each plot's data area is, its ranges and series
// colours).
#include <imgui.h>
#include <stb_image.h>
#include <sys/wait.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "acquisition/session/session_file.h"
#include "viewer/viewer_app.h"

namespace doorbench::testing {

// A session with one value channel `name` (physical values as given in `unit`, no
// calibration, range ±range) at rate_hz, with `metadata` (default: rig "viewer-test").
inline void write_channel_session(const std::filesystem::path& path, const std::string& name,
                                  const std::string& sensor_kind, const std::string& unit,
                                  double range, const std::vector<double>& values, double rate_hz,
                                  SessionMetadata metadata = {}) {
  if (metadata.rig_name.empty()) metadata.rig_name = "viewer-test";
  SessionWriter writer(path, metadata);
  ChannelInfo channel;
  channel.name = name;
  channel.sensor_kind = sensor_kind;
  channel.raw_type = RawType::kValues;
  channel.raw_unit = unit;
  channel.unit = unit;
  channel.range_min = -range;
  channel.range_max = range;
  channel.sample_rate_hz = rate_hz;
  writer.append_values(writer.add_channel(channel), values);
  writer.close();
}

// A session with one channel "force" (N, values as given, no calibration) at rate_hz.
inline void write_force_session(const std::filesystem::path& path,
                                const std::vector<double>& values, double rate_hz) {
  write_channel_session(path, "force", "imported", "N", 100, values, rate_hz);
}

struct Screenshot {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;  // row by row, y downwards
  nlohmann::json info;             // PNG.json
  const unsigned char* pixel(int x, int y) const {
    return rgb.data() + (std::size_t(y) * std::size_t(width) + std::size_t(x)) * 3;
  }
  // The plot whose title starts with `prefix`; throws when there is none.
  const nlohmann::json& plot(const std::string& prefix) const {
    for (const auto& p : info["plots"]) {
      if (p["title"].get<std::string>().rfind(prefix, 0) == 0) return p;
    }
    throw std::runtime_error("no plot titled " + prefix + "... in the screenshot");
  }
};

// One headless ImGui frame of the viewer's window (every layout as tabs): the plots drawn.
inline std::vector<std::string> window_frame_plots(viewer::Viewer& view) {
  ImGui::CreateContext();
  ImGuiIO& io = ImGui::GetIO();
  io.IniFilename = nullptr;
  io.DisplaySize = ImVec2(1200, 800);
  io.DeltaTime = 1.0f / 60.0f;
  unsigned char* texels = nullptr;
  int w = 0, h = 0;
  io.Fonts->GetTexDataAsRGBA32(&texels, &w, &h);
  std::vector<std::string> titles;
  for (int frame = 0; frame < 2; ++frame) {
    ImGui::NewFrame();
    view.frame(1200, 800);
    ImGui::Render();
  }
  for (const auto& p : view.plots()) titles.push_back(p.title);
  ImGui::DestroyContext();
  return titles;
}

// `with_info`: read PNG.json too (the viewer's screenshots have one, the station's not).
inline Screenshot load_screenshot(const std::filesystem::path& png, bool with_info = true) {
  Screenshot shot;
  int n = 0;
  unsigned char* pixels = stbi_load(png.string().c_str(), &shot.width, &shot.height, &n, 3);
  if (pixels == nullptr) throw std::runtime_error(png.string() + ": not a PNG");
  shot.rgb.assign(pixels, pixels + std::size_t(shot.width) * std::size_t(shot.height) * 3);
  stbi_image_free(pixels);
  if (!with_info) return shot;
  std::ifstream info(png.string() + ".json");
  shot.info = nlohmann::json::parse(info);
  return shot;
}

// `command` (a shell command line) under xvfb-run; returns its exit status, stderr in `err`.
inline int run_under_xvfb(const std::string& command, const std::filesystem::path& dir,
                          std::string& err) {
  const std::filesystem::path err_path = dir / "xvfb-stderr.txt";
  // -noreset: a command that opens and closes several windows (one X connection after
  // another) would otherwise meet the server resetting after the last client left, and fail
  // to open the display now and then.
  const std::string line = "xvfb-run -a -s '-screen 0 1600x1200x24 -noreset' " + command +
                           " >/dev/null 2>'" + err_path.string() + "'";
  const int status = std::system(line.c_str());
  std::ifstream in(err_path);
  std::ostringstream text;
  text << in.rdbuf();
  err = text.str();
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

inline bool near_rgb(const unsigned char* p, const std::vector<int>& rgb, int tolerance) {
  return std::abs(p[0] - rgb[0]) + std::abs(p[1] - rgb[1]) + std::abs(p[2] - rgb[2]) <= tolerance;
}

// Pixel geometry of one plot of a screenshot: value <-> pixel.
struct PlotGeometry {
  double x0, y0, w, h;  // data area
  double xmin, xmax, ymin, ymax;
  explicit PlotGeometry(const nlohmann::json& plot) {
    const std::vector<double> area = plot["area_px"];
    const std::vector<double> xr = plot["x_range"], yr = plot["y_range"];
    x0 = area[0], y0 = area[1], w = area[2], h = area[3];
    xmin = xr[0], xmax = xr[1], ymin = yr[0], ymax = yr[1];
  }
  double row_of(double value) const { return y0 + h - (value - ymin) / (ymax - ymin) * h; }
  double column_of(double x) const { return x0 + (x - xmin) / (xmax - xmin) * w; }
  double x_of(double column) const { return xmin + (column + 0.5 - x0) / w * (xmax - xmin); }
  int top() const { return int(std::ceil(y0)) + 1; }
  int bottom() const { return int(std::floor(y0 + h)) - 2; }
  int left() const { return int(std::ceil(x0)) + 1; }
  int right() const { return int(std::floor(x0 + w)) - 2; }
};

// The rows y = curve(x) spans over columns column ± half_width_px (a line's thickness):
// {lowest, highest}.
template <typename Curve>
std::pair<double, double> curve_rows(const PlotGeometry& plot, Curve&& curve, int column,
                                     double half_width_px) {
  double lo = 1e9, hi = -1e9;
  for (double dx = -half_width_px; dx <= half_width_px; dx += 0.25) {
    const double row = plot.row_of(curve(plot.x_of(column + dx)));
    lo = std::min(lo, row);
    hi = std::max(hi, row);
  }
  return {lo, hi};
}

// Requires, in 24 columns across the data area of `plot` in an RGB image `width` pixels
// wide, that the colour `rgb` is drawn where y = curve(x) passes (within 3 px of the rows it
// spans over ±1.5 px, the line's thickness) and nowhere else in the column.
template <typename Curve>
void require_curve_drawn_where_it_belongs(const unsigned char* pixels, int width,
                                          const PlotGeometry& plot, const std::vector<int>& rgb,
                                          Curve&& curve) {
  for (int k = 1; k <= 24; ++k) {
    const int px = int(plot.x0 + plot.w * k / 25.0);
    const auto [lo, hi] = curve_rows(plot, curve, px, 1.5);
    bool on_curve = false;
    for (int y = plot.top(); y <= plot.bottom(); ++y) {
      const unsigned char* p = pixels + (std::size_t(y) * std::size_t(width) + px) * 3;
      const bool coloured = near_rgb(p, rgb, 60);
      const bool near = y >= lo - 3.0 && y <= hi + 3.0;
      INFO("column " << px << ", row " << y << ", curve rows " << lo << ".." << hi);
      if (coloured) REQUIRE(near);  // the series colour nowhere else in the data area
      on_curve = on_curve || (coloured && near);
    }
    INFO("column " << px << ": curve expected at rows " << lo << ".." << hi);
    REQUIRE(on_curve);
  }
}

}  // namespace doorbench::testing
