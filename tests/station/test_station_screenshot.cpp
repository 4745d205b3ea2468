// The station draws the door where the geometry puts it: under Xvfb (Mesa's software
// OpenGL) a child run of this binary renders the door at three angles, for the built-in
// dishwasher and for a glTF box this test writes, and the door's free edge is found in the
// pixels within 2 px of where an independent pinhole projection of the scene's numbers
// puts it.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <fstream>

#include "fixtures/temp_dir.h"
#include "station/scene.h"
#include "station/station_session.h"
#include "station/station_window.h"
#include "tests/support/busy_processes.h"
#include "tests/support/gltf_box.h"
#include "tests/support/viewer_pixels.h"

using namespace doorbench;
namespace fs = std::filesystem;

namespace {

constexpr int kWidth = 800, kHeight = 600;
constexpr double kAngles[3] = {0.1, 0.45, 0.8};

// Flat colours (all ambient), so that the door's pixels are exactly its colour.
const char* kFlatLook = R"(
[lighting]
ambient = 1.0
diffuse = 0.0

[colours]
door_rgb = [1.0, 0.0, 0.0]
handle_rgb = [0.0, 0.0, 1.0]
cabinet_rgb = [0.0, 1.0, 0.0]
background_rgb = [0.0, 0.0, 0.0]
)";

void write_scenes(const fs::path& dir) {
  std::ofstream(dir / "default.toml") << kFlatLook;
  // A door 500 x 600 x 30 mm hinged along its bottom edge, seen from the right and above.
  testing::write_gltf_box(dir / "box.gltf", "door", {-250, 0, 0}, {250, 600, 30});
  std::ofstream(dir / "gltf.toml") << kFlatLook << R"(
[mesh]
file = "box.gltf"
units = "mm"

[hinge]
point_m = [0, 0, 0]
axis = [1, 0, 0]

[camera]
position_m = [0.3, 0.9, 1.4]
target_m = [0, 0.25, 0]
vertical_fov_deg = 45
)";
  // The dishwasher in each stereo mode: a 0.8 x 0.6 m screen (the window's 4:3) 1.8 m away.
  for (const std::string mode : {"side-by-side", "top-bottom", "quad-buffer"}) {
    std::ofstream(dir / (mode + ".toml"))
        << kFlatLook << "\n[stereo]\nmode = \"" << mode << "\"\neye_separation_m = 0.065\n"
        << "screen_width_m = 0.8\nscreen_height_m = 0.6\n"
        << "screen_distance_m = 1.8\n";
  }
}

using V3 = std::array<double, 3>;

// The test's own pinhole camera: pixel (column, row from the top) of a point, for the mono
// camera (its field of view) or one eye of a stereo pair (a parallel eye half the eye
// separation to the side, projecting onto the physical screen), drawn into the image
// region x0, y0, w, h.
struct Pinhole {
  V3 eye, s, u, f;
  double tan_half = 0, offset = 0, screen_w = 0, screen_h = 0, screen_d = 0;
  bool stereo = false;
  double x0 = 0, y0 = 0, w = kWidth, h = kHeight;
  explicit Pinhole(const station::Camera& c) : eye(c.position_m) {
    V3 d{c.target_m[0] - eye[0], c.target_m[1] - eye[1], c.target_m[2] - eye[2]};
    f = norm(d);
    s = norm(cross(f, c.up));
    u = cross(s, f);
    tan_half = std::tan(c.vertical_fov_rad / 2);
  }
  Pinhole(const station::Scene& scene, double eye_sign, double x0_px, double y0_px, double w_px,
          double h_px)
      : Pinhole(scene.camera) {
    stereo = true;
    offset = eye_sign * scene.stereo.eye_separation_m / 2;
    for (int i = 0; i < 3; ++i) eye[i] += offset * s[i];
    screen_w = scene.stereo.screen_width_m;
    screen_h = scene.stereo.screen_height_m;
    screen_d = scene.stereo.screen_distance_m;
    x0 = x0_px, y0 = y0_px, w = w_px, h = h_px;
  }
  static V3 cross(const V3& a, const V3& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  }
  static double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
  static V3 norm(const V3& a) {
    const double n = std::sqrt(dot(a, a));
    return {a[0] / n, a[1] / n, a[2] / n};
  }
  std::array<double, 2> pixel(const V3& p) const {
    const V3 d{p[0] - eye[0], p[1] - eye[1], p[2] - eye[2]};
    const double x = dot(d, s), y = dot(d, u), z = dot(d, f);
    if (stereo) {
      // Where the ray from the eye meets the screen, from the screen's centre (which is
      // straight ahead of the camera, so `offset` to the eye's side).
      const double sx = x * screen_d / z + offset, sy = y * screen_d / z;
      return {x0 + (sx / screen_w + 0.5) * w, y0 + (0.5 - sy / screen_h) * h};
    }
    return {x0 + (x / (z * tan_half * (w / h)) + 1) / 2 * w, y0 + (1 - y / (z * tan_half)) / 2 * h};
  }
};

// A door point at θ about the x axis through (0, hinge_y, 0).
V3 turned(const V3& p, double hinge_y, double theta) {
  const double dy = p[1] - hinge_y, dz = p[2];
  return {p[0], hinge_y + dy * std::cos(theta) - dz * std::sin(theta),
          dy * std::sin(theta) + dz * std::cos(theta)};
}

struct DoorBox {
  double x0, x1, y_hinge, y_edge, thickness;
};

// The row, at `column`, of the free edge's line through (x0, y_edge, z) and (x1, y_edge, z)
// at θ, for the back (z 0) and the front (z thickness) of the door, whichever is higher in
// the image (the door's outer face is towards the camera at these angles).
double expected_edge_row(const Pinhole& camera, const DoorBox& door, double theta, double column) {
  double best = 1e9;
  for (const double z : {0.0, door.thickness}) {
    const auto a = camera.pixel(turned({door.x0, door.y_edge, z}, door.y_hinge, theta));
    const auto b = camera.pixel(turned({door.x1, door.y_edge, z}, door.y_hinge, theta));
    const double t = (column - a[0]) / (b[0] - a[0]);
    best = std::min(best, a[1] + t * (b[1] - a[1]));
  }
  return best;
}

// The topmost door-coloured row in `column`, scanning up from `inside` (a row inside the
// door) while the pixels stay the door's colour.
int found_edge_row(const testing::Screenshot& shot, int column, int inside) {
  const std::vector<int> red{255, 0, 0};
  REQUIRE(testing::near_rgb(shot.pixel(column, inside), red, 30));
  int row = inside;
  while (row > 0 && testing::near_rgb(shot.pixel(column, row - 1), red, 30)) --row;
  return row;
}

void check_view(const testing::Screenshot& shot, const Pinhole& camera, const DoorBox& door,
                double theta, const std::string& what) {
  // Three columns across the door (clear of the handle, which spans the middle two thirds
  // of the dishwasher's door).
  for (const double across : {0.05, 0.12, 0.9}) {
    const double x = door.x0 + across * (door.x1 - door.x0);
    const double mid_y = door.y_hinge + 0.6 * (door.y_edge - door.y_hinge);
    const auto inside = camera.pixel(turned({x, mid_y, door.thickness}, door.y_hinge, theta));
    const int column = int(std::lround(inside[0]));
    const double expected = expected_edge_row(camera, door, theta, column + 0.5);
    const int found = found_edge_row(shot, column, int(std::lround(inside[1])));
    INFO(what << " at " << theta << " rad, column " << column << ": edge expected at row "
              << expected << ", found " << found);
    CHECK(std::abs(found + 0.5 - expected) <= 2.0);
  }
}

void check_edges(const fs::path& dir, const std::string& name, const DoorBox& door) {
  const station::Scene scene = station::load_scene(dir / (name + ".toml"));
  const Pinhole camera(scene.camera);
  for (int k = 0; k < 3; ++k) {
    const testing::Screenshot shot =
        testing::load_screenshot(dir / (name + std::to_string(k) + ".png"), false);
    REQUIRE(shot.width == kWidth);
    REQUIRE(shot.height == kHeight);
    check_view(shot, camera, door, kAngles[k], name);
  }
}

}  // namespace

TEST_CASE("station screenshots at three angles and in stereo (child of the tests below)",
          "[.][child]") {
  const char* dir_text = std::getenv("DOORBENCH_TEST_DIR");
  REQUIRE(dir_text != nullptr);
  const fs::path dir = dir_text;
  station::StationWindowOptions options;
  options.width_px = kWidth;
  options.height_px = kHeight;
  for (const std::string name : {"default", "gltf"}) {
    const station::Scene scene = station::load_scene(dir / (name + ".toml"));
    for (int k = 0; k < 3; ++k) {
      station::station_screenshot(scene, kAngles[k], dir / (name + std::to_string(k) + ".png"),
                                  options);
    }
  }
  for (const std::string mode : {"side-by-side", "top-bottom", "quad-buffer"}) {
    const station::Scene scene = station::load_scene(dir / (mode + ".toml"));
    const station::StereoMode drawn =
        station::station_screenshot(scene, kAngles[1], dir / (mode + ".png"), options);
    std::ofstream(dir / (mode + ".drawn")) << station::to_string(drawn);
  }
}

TEST_CASE("the station draws the door's edge where the geometry puts it, within 2 px",
          "[station][xvfb]") {
  testing::TempDir dir("station_screenshot");
  write_scenes(dir.path);
  const fs::path self = fs::read_symlink("/proc/self/exe");
  std::string err;
  const int status = testing::run_under_xvfb(
      "env DOORBENCH_TEST_DIR='" + dir.path.string() + "' '" + self.string() +
          "' 'station screenshots at three angles and in stereo (child of the tests below)'",
      dir.path, err);
  INFO("stderr: " << err);
  REQUIRE(status == 0);
  // The built-in dishwasher's door: 0.6 m wide, hinged at y 0.1 m, its top at 0.82 m, 40 mm
  // thick; the glTF box: 0.5 m wide, hinged at 0, 0.6 m high, 30 mm thick.
  check_edges(dir.path, "default", {-0.3, 0.3, 0.1, 0.82, 0.04});
  check_edges(dir.path, "gltf", {-0.25, 0.25, 0.0, 0.6, 0.03});
}

TEST_CASE("the station's stereo: each eye's view where the screen's geometry puts it",
          "[station][xvfb]") {
  testing::TempDir dir("station_stereo");
  write_scenes(dir.path);
  const fs::path self = fs::read_symlink("/proc/self/exe");
  std::string err;
  const int status = testing::run_under_xvfb(
      "env DOORBENCH_TEST_DIR='" + dir.path.string() + "' '" + self.string() +
          "' 'station screenshots at three angles and in stereo (child of the tests below)'",
      dir.path, err);
  INFO("stderr: " << err);
  REQUIRE(status == 0);
  const DoorBox door{-0.3, 0.3, 0.1, 0.82, 0.04};
  const double theta = kAngles[1];
  const auto shot_of = [&](const std::string& mode) {
    return testing::load_screenshot(dir.path / (mode + ".png"), false);
  };
  const station::Scene sbs = station::load_scene(dir.path / "side-by-side.toml");
  const testing::Screenshot side = shot_of("side-by-side");
  check_view(side, Pinhole(sbs, -1, 0, 0, kWidth / 2, kHeight), door, theta, "left eye");
  check_view(side, Pinhole(sbs, +1, kWidth / 2, 0, kWidth / 2, kHeight), door, theta, "right eye");
  const testing::Screenshot top = shot_of("top-bottom");
  check_view(top, Pinhole(sbs, -1, 0, 0, kWidth, kHeight / 2), door, theta, "left eye (top)");
  check_view(top, Pinhole(sbs, +1, 0, kHeight / 2, kWidth, kHeight / 2), door, theta,
             "right eye (bottom)");
  // Quad-buffer where the display offers it (its back-left buffer is read), else mono.
  std::ifstream drawn_in(dir.path / "quad-buffer.drawn");
  std::string drawn;
  drawn_in >> drawn;
  INFO("quad-buffer drawn as " << drawn);
  const testing::Screenshot quad = shot_of("quad-buffer");
  if (drawn == "mono") {
    check_view(quad, Pinhole(sbs.camera), door, theta, "quad-buffer's mono fallback");
  } else {
    REQUIRE(drawn == "quad-buffer");
    check_view(quad, Pinhole(sbs, -1, 0, 0, kWidth, kHeight), door, theta, "left buffer");
  }
}

namespace {

// The pixels of `shot` within 30 of `rgb`.
int pixels_of(const testing::Screenshot& shot, const std::vector<int>& rgb) {
  int count = 0;
  for (int y = 0; y < shot.height; ++y) {
    for (int x = 0; x < shot.width; ++x) count += testing::near_rgb(shot.pixel(x, y), rgb, 30);
  }
  return count;
}

}  // namespace

// Run by the test below: the live station (its own thread, as in a campaign run) opened with
// the flat red-door scene, a frame captured; the blue-door scene staged, a frame captured;
// back to its own, a frame captured; the station's report written to report.txt.
TEST_CASE("station staging: a live station switches scenes (child of the test below)",
          "[.][child]") {
  const char* dir_text = std::getenv("DOORBENCH_TEST_DIR");
  REQUIRE(dir_text != nullptr);
  const fs::path dir = dir_text;
  station::StationRequest request;
  request.scene_file = dir / "default.toml";
  request.scenes = {dir / "blue.toml"};
  request.sound = false;
  request.window.fullscreen = false;
  request.window.width_px = kWidth;
  request.window.height_px = kHeight;
  station::StationSession session(request);
  session.start();
  session.station()->capture(dir / "own.png");
  session.stage(dir / "blue.toml", {});
  session.station()->capture(dir / "staged.png");
  const station::StationReport staged = session.station()->report();
  session.stage({}, {});
  session.station()->capture(dir / "own-again.png");
  const station::StationReport again = session.station()->report();
  session.close();
  std::ofstream(dir / "report.txt") << staged.scene << "\n"
                                    << staged.scene_changes << "\n"
                                    << again.scene << "\n"
                                    << again.scene_changes << "\n";
}

TEST_CASE("the live station draws the scene a presentation is staged in, then its own again",
          "[station][xvfb]") {
  testing::TempDir dir("station_staging");
  write_scenes(dir.path);
  std::string blue = kFlatLook;
  blue.replace(blue.find("door_rgb = [1.0, 0.0, 0.0]"), 26, "door_rgb = [0.0, 0.0, 1.0]");
  blue.replace(blue.find("handle_rgb = [0.0, 0.0, 1.0]"), 28, "handle_rgb = [1.0, 1.0, 0.0]");
  std::ofstream(dir.path / "blue.toml") << blue;
  testing::BusyProcesses busy(2);
  const fs::path self = fs::read_symlink("/proc/self/exe");
  std::string err;
  const int status = testing::run_under_xvfb(
      "env DOORBENCH_TEST_DIR='" + dir.path.string() + "' '" + self.string() +
          "' 'station staging: a live station switches scenes (child of the test below)'",
      dir.path, err);
  INFO("stderr: " << err);
  REQUIRE(status == 0);
  const std::vector<int> red = {255, 0, 0}, blue_door = {0, 0, 255};
  const testing::Screenshot own = testing::load_screenshot(dir.path / "own.png", false);
  const testing::Screenshot staged = testing::load_screenshot(dir.path / "staged.png", false);
  const testing::Screenshot again = testing::load_screenshot(dir.path / "own-again.png", false);
  // The door fills a good part of the window in either scene: red in the station's own, blue
  // (and no red) in the staged one.
  const int door_pixels = pixels_of(own, red);
  CHECK(door_pixels > kWidth * kHeight / 20);
  CHECK(pixels_of(staged, red) == 0);
  CHECK(pixels_of(staged, blue_door) > kWidth * kHeight / 20);
  // The staged scene's handle is yellow; the own scene has none.
  const std::vector<int> yellow = {255, 255, 0};
  CHECK(pixels_of(own, yellow) == 0);
  CHECK(pixels_of(staged, yellow) > 100);
  CHECK(pixels_of(again, red) == door_pixels);
  std::ifstream report(dir.path / "report.txt");
  std::string staged_scene, staged_changes, again_scene, again_changes;
  std::getline(report, staged_scene);
  std::getline(report, staged_changes);
  std::getline(report, again_scene);
  std::getline(report, again_changes);
  CHECK(staged_scene == (dir.path / "blue.toml").string());
  CHECK(staged_changes == "1");
  CHECK(again_scene == (dir.path / "default.toml").string());
  CHECK(again_changes == "2");
}
