// The scene file's reader (station/scene.h): TOML through toml++, every error naming the
// file, the line and the key.
#include <toml++/toml.h>

#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "core/number_format.h"
#include "core/units.h"
#include "station/scene.h"

namespace doorbench::station {
namespace {

// The keys each table may hold; anything else is refused by name (a misspelt key would
// otherwise be ignored silently).
const std::map<std::string, std::set<std::string>>& known_keys() {
  static const std::map<std::string, std::set<std::string>> keys = {
      {"mesh", {"file", "units", "door_nodes"}},
      {"hinge", {"point_m", "axis"}},
      {"handle", {"position_m"}},
      {"camera", {"position_m", "target_m", "up", "vertical_fov_deg", "near_m", "far_m"}},
      {"lighting", {"direction", "ambient", "diffuse"}},
      {"colours", {"door_rgb", "handle_rgb", "cabinet_rgb", "background_rgb"}},
      {"sound",
       {"latch_wav", "stop_wav", "hinge_wav", "latch_gain", "stop_gain", "hinge_gain",
        "hinge_full_speed_rad_s"}},
      {"stereo",
       {"mode", "eye_separation_m", "screen_width_m", "screen_height_m", "screen_distance_m"}},
  };
  return keys;
}

class SceneReader {
 public:
  SceneReader(std::filesystem::path path, toml::table root)
      : path_(std::move(path)), root_(std::move(root)) {}

  [[noreturn]] void fail(const toml::node* node, const std::string& key,
                         const std::string& what) const {
    std::ostringstream message;
    message << path_.string();
    if (node != nullptr && node->source().begin.line > 0) {
      message << ":" << node->source().begin.line;
    }
    message << ": " << key << ": " << what;
    throw SceneError(message.str());
  }

  void check_keys() const {
    for (const auto& [table_key, node] : root_) {
      const std::string table(table_key.str());
      const auto known = known_keys().find(table);
      if (known == known_keys().end()) fail(&node, table, "not a table of a scene file");
      const toml::table* entries = node.as_table();
      if (entries == nullptr) fail(&node, table, "expected a table ([" + table + "])");
      for (const auto& [key, value] : *entries) {
        if (!known->second.contains(std::string(key.str()))) {
          fail(&value, table + "." + std::string(key.str()), "not a key of [" + table + "]");
        }
      }
    }
  }

  const toml::node* find(const std::string& table, const std::string& key) const {
    const toml::table* entries = root_[table].as_table();
    return entries == nullptr ? nullptr : entries->get(key);
  }
  bool has_table(const std::string& table) const { return root_.contains(table); }

  void number(const std::string& table, const std::string& key, double& out, double lo,
              double hi) const {
    const toml::node* node = find(table, key);
    if (node == nullptr) return;
    const std::optional<double> value = node->value<double>();
    const std::string name = table + "." + key;
    if (!value || !std::isfinite(*value)) fail(node, name, "expected a number");
    if (*value < lo || *value > hi) {
      fail(node, name,
           "must be in [" + format_number(lo) + ", " + format_number(hi) + "] (got " +
               format_number(*value) + ")");
    }
    out = *value;
  }

  void vector(const std::string& table, const std::string& key, Vec3& out,
              bool unit = false) const {
    const toml::node* node = find(table, key);
    if (node == nullptr) return;
    const std::string name = table + "." + key;
    const toml::array* array = node->as_array();
    if (array == nullptr || array->size() != 3) {
      fail(node, name,
           "expected 3 numbers [x, y, z], got " +
               (array ? std::to_string(array->size()) + " items" : std::string("no array")));
    }
    Vec3 v;
    for (int i = 0; i < 3; ++i) {
      const std::optional<double> value = (*array)[i].value<double>();
      if (!value || !std::isfinite(*value)) fail(node, name, "expected 3 numbers [x, y, z]");
      v[i] = *value;
    }
    if (unit) {
      const double norm = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
      if (!(norm > 1e-9)) fail(node, name, "must not be zero (a direction)");
      for (double& c : v) c /= norm;
    }
    out = v;
  }

  void colour(const std::string& key, Rgb& out) const {
    Vec3 v{out[0], out[1], out[2]};
    vector("colours", key, v);
    for (const double c : v) {
      if (c < 0.0 || c > 1.0) fail(find("colours", key), "colours." + key, "each in [0, 1]");
    }
    out = {float(v[0]), float(v[1]), float(v[2])};
  }

  std::string text(const std::string& table, const std::string& key) const {
    const toml::node* node = find(table, key);
    if (node == nullptr) return "";
    const std::optional<std::string> value = node->value<std::string>();
    if (!value) fail(node, table + "." + key, "expected a string");
    return *value;
  }

  // A path in the file, relative to the scene file's folder; it must exist.
  std::filesystem::path file(const std::string& table, const std::string& key) const {
    const std::string value = text(table, key);
    if (value.empty()) return {};
    std::filesystem::path file = value;
    if (file.is_relative()) file = path_.parent_path() / file;
    if (!std::filesystem::is_regular_file(file)) {
      fail(find(table, key), table + "." + key, "no such file: " + file.string());
    }
    return file;
  }

  std::vector<std::string> names(const std::string& table, const std::string& key,
                                 bool& given) const {
    const toml::node* node = find(table, key);
    given = node != nullptr;
    std::vector<std::string> out;
    if (node == nullptr) return out;
    const toml::array* array = node->as_array();
    if (array == nullptr) fail(node, table + "." + key, "expected an array of node names");
    for (const toml::node& item : *array) {
      const std::optional<std::string> name = item.value<std::string>();
      if (!name) fail(node, table + "." + key, "expected an array of node names");
      out.push_back(*name);
    }
    return out;
  }

  double metres_per_unit() const {
    const std::string units = text("mesh", "units");
    if (units.empty() || units == "m") return 1.0;
    if (units == "cm") return 0.01;
    if (units == "mm") return 0.001;
    if (units == "in") return 0.0254;
    fail(find("mesh", "units"), "mesh.units", "'" + units + "' is not one of m, cm, mm, in");
  }

  StereoMode stereo_mode() const {
    const std::string mode = text("stereo", "mode");
    if (mode.empty() || mode == "mono") return StereoMode::kMono;
    if (mode == "quad-buffer") return StereoMode::kQuadBuffer;
    if (mode == "side-by-side") return StereoMode::kSideBySide;
    if (mode == "top-bottom") return StereoMode::kTopBottom;
    fail(find("stereo", "mode"), "stereo.mode",
         "'" + mode + "' is not one of mono, quad-buffer, side-by-side, top-bottom");
  }

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  toml::table root_;
};

void read_view(const SceneReader& in, Scene& scene) {
  in.vector("camera", "position_m", scene.camera.position_m);
  in.vector("camera", "target_m", scene.camera.target_m);
  in.vector("camera", "up", scene.camera.up, true);
  double fov_deg = scene.camera.vertical_fov_rad * kDegPerRad;
  in.number("camera", "vertical_fov_deg", fov_deg, 5.0, 150.0);
  scene.camera.vertical_fov_rad = fov_deg * kRadPerDeg;
  in.number("camera", "near_m", scene.camera.near_m, 1e-4, 10.0);
  in.number("camera", "far_m", scene.camera.far_m, 0.1, 1e4);
  if (!(scene.camera.far_m > scene.camera.near_m)) {
    in.fail(in.find("camera", "far_m"), "camera.far_m", "must be greater than camera.near_m");
  }
  in.vector("lighting", "direction", scene.lighting.direction, true);
  in.number("lighting", "ambient", scene.lighting.ambient, 0.0, 1.0);
  in.number("lighting", "diffuse", scene.lighting.diffuse, 0.0, 1.0);
  in.colour("door_rgb", scene.colours.door);
  in.colour("handle_rgb", scene.colours.handle);
  in.colour("cabinet_rgb", scene.colours.cabinet);
  in.colour("background_rgb", scene.colours.background);
  scene.stereo.mode = in.stereo_mode();
  in.number("stereo", "eye_separation_m", scene.stereo.eye_separation_m, 0.0, 0.2);
  in.number("stereo", "screen_width_m", scene.stereo.screen_width_m, 0.05, 50.0);
  in.number("stereo", "screen_height_m", scene.stereo.screen_height_m, 0.05, 50.0);
  in.number("stereo", "screen_distance_m", scene.stereo.screen_distance_m, 0.05, 50.0);
}

void read_sound(const SceneReader& in, Scene& scene) {
  scene.sounds.latch_wav = in.file("sound", "latch_wav");
  scene.sounds.stop_wav = in.file("sound", "stop_wav");
  scene.sounds.hinge_wav = in.file("sound", "hinge_wav");
  in.number("sound", "latch_gain", scene.sounds.latch_gain, 0.0, 4.0);
  in.number("sound", "stop_gain", scene.sounds.stop_gain, 0.0, 4.0);
  in.number("sound", "hinge_gain", scene.sounds.hinge_gain, 0.0, 4.0);
  in.number("sound", "hinge_full_speed_rad_s", scene.sounds.hinge_full_speed_rad_s, 0.01, 100.0);
}

}  // namespace

const char* to_string(StereoMode mode) {
  switch (mode) {
    case StereoMode::kQuadBuffer:
      return "quad-buffer";
    case StereoMode::kSideBySide:
      return "side-by-side";
    case StereoMode::kTopBottom:
      return "top-bottom";
    case StereoMode::kMono:
      break;
  }
  return "mono";
}

namespace {

// The scene file (or sound set) at `path`, parsed and its tables and keys checked.
SceneReader read_scene_file(const std::filesystem::path& path, const char* what) {
  if (!std::filesystem::is_regular_file(path)) {
    throw SceneError(path.string() + ": no such " + what);
  }
  toml::table root;
  try {
    root = toml::parse_file(path.string());
  } catch (const toml::parse_error& error) {
    std::ostringstream message;
    message << path.string() << ":" << error.source().begin.line << ": " << error.description();
    throw SceneError(message.str());
  }
  SceneReader in(path, std::move(root));
  in.check_keys();
  return in;
}

}  // namespace

Sounds load_sound_set(const std::filesystem::path& path) {
  const SceneReader in = read_scene_file(path, "sound set");
  if (!in.has_table("sound")) {
    throw SceneError(path.string() +
                     ": no [sound] table (a sound set is the [sound] table of a "
                     "scene file: latch_wav, stop_wav, hinge_wav, ...)");
  }
  Scene scene = default_scene();
  read_sound(in, scene);
  return scene.sounds;
}

Scene load_scene(const std::filesystem::path& path) {
  const SceneReader in = read_scene_file(path, "scene file");
  Scene scene = default_scene();
  scene.source = path.string();
  in.vector("hinge", "point_m", scene.hinge_point_m);
  in.vector("hinge", "axis", scene.hinge_axis, true);
  in.vector("handle", "position_m", scene.handle_m);
  read_view(in, scene);
  read_sound(in, scene);
  if (in.has_table("mesh")) {
    const std::filesystem::path mesh = in.file("mesh", "file");
    if (mesh.empty()) in.fail(in.find("mesh", "file"), "mesh.file", "missing (the mesh to draw)");
    bool door_nodes_given = false;
    std::vector<std::string> door_nodes = in.names("mesh", "door_nodes", door_nodes_given);
    if (!door_nodes_given) door_nodes = {"door"};
    scene.parts =
        import_mesh(mesh, in.metres_per_unit(), door_nodes, door_nodes_given, scene.colours);
  } else {
    for (MeshPart& part : scene.parts) {
      part.rgb = part.name == "door"     ? scene.colours.door
                 : part.name == "handle" ? scene.colours.handle
                                         : scene.colours.cabinet;
    }
  }
  return scene;
}

}  // namespace doorbench::station
