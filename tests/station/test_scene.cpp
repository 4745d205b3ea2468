// The station's scene: the built-in dishwasher, scene files and meshes in glTF, OBJ and STL
// through assimp, and the errors a lab meets, word for word.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>

#include "fixtures/temp_dir.h"
#include "station/scene.h"
#include "tests/support/gltf_box.h"

using namespace doorbench;
using namespace doorbench::station;
namespace fs = std::filesystem;

namespace {

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

// The extent of every vertex of the parts that (do not) move with the door.
std::array<double, 6> extent(const Scene& scene, bool moving) {
  std::array<double, 6> box{1e9, 1e9, 1e9, -1e9, -1e9, -1e9};
  for (const MeshPart& part : scene.parts) {
    if (part.moves_with_door != moving) continue;
    for (std::size_t i = 0; i < part.positions_m.size(); ++i) {
      box[i % 3] = std::min(box[i % 3], double(part.positions_m[i]));
      box[3 + i % 3] = std::max(box[3 + i % 3], double(part.positions_m[i]));
    }
  }
  return box;
}

std::string error_of(const fs::path& path) {
  try {
    load_scene(path);
  } catch (const SceneError& error) {
    return error.what();
  }
  return "(no error)";
}

}  // namespace

TEST_CASE("station scene: the built-in dishwasher has a cabinet, a door and a handle on it",
          "[station]") {
  const Scene scene = default_scene();
  REQUIRE(scene.parts.size() == 3);
  CHECK(scene.parts[0].name == "cabinet");
  CHECK_FALSE(scene.parts[0].moves_with_door);
  CHECK(scene.parts[1].moves_with_door);
  CHECK(scene.parts[2].moves_with_door);
  for (const MeshPart& part : scene.parts) {
    CHECK(part.vertex_count() % 3 == 0);
    CHECK(part.normals.size() == part.positions_m.size());
  }
  // The handle is where the reference door's hand pushes: 0.58 m from the hinge.
  const double dy = scene.handle_m[1] - scene.hinge_point_m[1];
  const double dz = scene.handle_m[2] - scene.hinge_point_m[2];
  CHECK(std::hypot(dy, dz) == Approx(0.58).margin(0.01));
  // Opening a quarter turn lays the door's top edge forwards (+z) at hinge height.
  const Vec3 top = door_point_at(scene, {0.0, 0.82, 0.0}, std::acos(-1.0) / 2);
  CHECK(top[1] == Approx(0.1).margin(1e-12));
  CHECK(top[2] == Approx(0.72));
}

TEST_CASE("station scene: a glTF mesh in millimetres, its door node and the file's settings",
          "[station]") {
  testing::TempDir dir("station_scene");
  testing::write_gltf_box(dir.path / "door.gltf", "door", {-300, 100, 0}, {300, 800, 40});
  write_text(dir.path / "scene.toml", R"([mesh]
file = "door.gltf"
units = "mm"

[hinge]
point_m = [0, 0.1, 0]
axis = [2, 0, 0]

[camera]
position_m = [0, 1, 2]
vertical_fov_deg = 30

[stereo]
mode = "side-by-side"
eye_separation_m = 0.06
)");
  const Scene scene = load_scene(dir.path / "scene.toml");
  REQUIRE(scene.parts.size() == 1);
  CHECK(scene.parts[0].name == "door");
  CHECK(scene.parts[0].moves_with_door);
  CHECK(scene.parts[0].vertex_count() == 36);
  const auto box = extent(scene, true);
  CHECK(box[0] == Approx(-0.3));
  CHECK(box[1] == Approx(0.1));
  CHECK(box[4] == Approx(0.8));
  CHECK(box[5] == Approx(0.04));
  CHECK(scene.hinge_axis[0] == Approx(1.0));  // made a unit vector
  CHECK(scene.camera.position_m[2] == 2.0);
  CHECK(scene.camera.vertical_fov_rad == Approx(30.0 * std::acos(-1.0) / 180.0));
  CHECK(scene.stereo.mode == StereoMode::kSideBySide);
  CHECK(scene.stereo.eye_separation_m == 0.06);
}

TEST_CASE("station scene: OBJ and STL meshes, and without a door node the whole mesh is the door",
          "[station]") {
  testing::TempDir dir("station_scene_formats");
  write_text(dir.path / "panel.obj", R"(o door
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
f 1 2 3 4
o cabinet
v 0 0 -1
v 1 0 -1
v 1 1 -1
f 5 6 7
)");
  write_text(dir.path / "obj.toml", "[mesh]\nfile = \"panel.obj\"\nunits = \"cm\"\n");
  const Scene obj = load_scene(dir.path / "obj.toml");
  const auto door = extent(obj, true);
  const auto cabinet = extent(obj, false);
  CHECK(door[3] == Approx(0.01));  // cm
  CHECK(door[5] == Approx(0.0));
  CHECK(cabinet[2] == Approx(-0.01));

  write_text(dir.path / "panel.stl", R"(solid panel
facet normal 0 0 1
outer loop
vertex 0 0 0
vertex 2 0 0
vertex 2 3 0
endloop
endfacet
endsolid panel
)");
  write_text(dir.path / "stl.toml", "[mesh]\nfile = \"panel.stl\"\nunits = \"in\"\n");
  const Scene stl = load_scene(dir.path / "stl.toml");
  const auto all = extent(stl, true);
  CHECK(all[3] == Approx(2 * 0.0254));
  CHECK(all[4] == Approx(3 * 0.0254));
  CHECK(extent(stl, false)[0] == 1e9);  // nothing static
}

TEST_CASE("station scene: errors name the file, the line and the key", "[station]") {
  testing::TempDir dir("station_scene_errors");
  const fs::path file = dir.path / "scene.toml";
  const std::string name = file.string();
  write_text(file, "[camera]\nposition_m = [0, 1]\n");
  CHECK(error_of(file) ==
        name + ":2: camera.position_m: expected 3 numbers [x, y, z], got 2 items");
  write_text(file, "[camera]\nfov = 30\n");
  CHECK(error_of(file) == name + ":2: camera.fov: not a key of [camera]");
  write_text(file, "[lighting]\nambient = 2\n");
  CHECK(error_of(file) == name + ":2: lighting.ambient: must be in [0, 1] (got 2)");
  write_text(file, "[mesh]\nfile = \"missing.gltf\"\n");
  CHECK(error_of(file) ==
        name + ":2: mesh.file: no such file: " + (dir.path / "missing.gltf").string());
  write_text(file, "[stereo]\nmode = \"anaglyph\"\n");
  CHECK(
      error_of(file) ==
      name +
          ":2: stereo.mode: 'anaglyph' is not one of mono, quad-buffer, side-by-side, top-bottom");
  testing::write_gltf_box(dir.path / "box.gltf", "box", {0, 0, 0}, {1, 1, 1});
  write_text(file, "[mesh]\nfile = \"box.gltf\"\ndoor_nodes = [\"door\"]\n");
  CHECK(error_of(file) ==
        (dir.path / "box.gltf").string() + ": mesh.door_nodes: no node named 'door' in the mesh");
  write_text(dir.path / "broken.gltf", "{ not json");
  write_text(file, "[mesh]\nfile = \"broken.gltf\"\n");
  CHECK_THAT(error_of(file), Catch::Matchers::StartsWith((dir.path / "broken.gltf").string() +
                                                         ": cannot read the mesh: "));
  write_text(file, "[camera\n");
  CHECK_THAT(error_of(file), Catch::Matchers::StartsWith(name + ":1: "));
  CHECK(error_of(dir.path / "none.toml") ==
        (dir.path / "none.toml").string() + ": no such scene file");
}
