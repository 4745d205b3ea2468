#pragma once
// The participant's station's scene (docs/station.md): the door's geometry, where it turns,
// where the handle is, how it is seen (camera, lighting, colours, stereo and the screen's
// geometry) and heard (sound files and levels). Read from a small TOML file beside the mesh a
// lab exports from CAD (glTF 2.0, OBJ, STL: anything assimp reads), or the built-in
// dishwasher (cabinet, door, handle) generated in code.
//
// Frame: one right-handed frame in metres for everything (the mesh after its `units`); the
// door turns by +θ about `hinge.axis` (right-hand rule) through `hinge.point_m`, θ being the
// playback's angle (0 closed).
//
// A Scene is a constant value once loaded; any thread may read it.
#include <array>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace doorbench::station {

using Vec3 = std::array<double, 3>;
using Rgb = std::array<float, 3>;  // 0..1

// One piece of the mesh as triangles: three vertices per triangle, xyz per vertex (metres),
// a unit normal per vertex.
struct MeshPart {
  std::string name;
  bool moves_with_door = false;
  Rgb rgb{0.7f, 0.7f, 0.7f};
  std::vector<float> positions_m;
  std::vector<float> normals;
  std::size_t vertex_count() const { return positions_m.size() / 3; }
};

struct Camera {
  Vec3 position_m{0.0, 1.35, 1.7};
  Vec3 target_m{0.0, 0.45, 0.15};
  Vec3 up{0.0, 1.0, 0.0};
  double vertical_fov_rad = 0.0;  // set from vertical_fov_deg (default 40°)
  double near_m = 0.05, far_m = 20.0;
};

struct Lighting {
  Vec3 direction{0.3, 1.0, 0.8};  // towards the light
  double ambient = 0.35;          // 0..1
  double diffuse = 0.75;          // 0..1
};

struct Colours {
  Rgb door{0.82f, 0.83f, 0.85f};
  Rgb handle{0.25f, 0.25f, 0.28f};
  Rgb cabinet{0.45f, 0.47f, 0.5f};
  Rgb background{0.12f, 0.13f, 0.16f};
};

// WAV files (any format libsndfile reads) for the door's sounds; empty: the built-in sound.
struct Sounds {
  std::filesystem::path latch_wav, stop_wav, hinge_wav;
  double latch_gain = 1.0, stop_gain = 1.0, hinge_gain = 0.5;  // 0..4
  double hinge_full_speed_rad_s = 2.0;  // the hinge sound's gain reaches hinge_gain here
};

enum class StereoMode { kMono, kQuadBuffer, kSideBySide, kTopBottom };
const char* to_string(StereoMode mode);

// The physical screen the participant faces, for the stereo frustums: its size and the
// viewer's distance from it (the camera is the midpoint between the eyes).
struct Stereo {
  StereoMode mode = StereoMode::kMono;
  double eye_separation_m = 0.065;
  double screen_width_m = 1.2, screen_height_m = 0.75, screen_distance_m = 1.5;
};

struct Scene {
  std::string source;  // the scene file, or "built-in dishwasher"
  std::vector<MeshPart> parts;
  Vec3 hinge_point_m{0.0, 0.1, 0.0};
  Vec3 hinge_axis{1.0, 0.0, 0.0};  // unit
  Vec3 handle_m{0.0, 0.68, 0.065};
  Camera camera;
  Lighting lighting;
  Colours colours;
  Sounds sounds;
  Stereo stereo;
};

// A scene file or its mesh that cannot be used: the message names the file, the line where
// known, and the key ("scene.toml:7: camera.position_m: expected 3 numbers, got 2").
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The built-in dishwasher: a cabinet 0.6 m wide and 0.82 m high, a door hinged along its
// bottom front edge (axis +x, opening towards +z, the viewer) and a bar handle 0.58 m from the
// hinge, with the default camera, lighting, colours and sounds.
Scene default_scene();

// Reads a scene file; every key is optional except mesh.file when [mesh] is given (without a
// [mesh] table the built-in dishwasher is drawn with the file's other settings). Throws
// SceneError naming the file, line and key.
Scene load_scene(const std::filesystem::path& path);

// A sound set (a campaign variant's `sounds`): the [sound] table of a TOML file, read as a
// scene file's (paths relative to the file, which must exist); the file's other tables, if
// any, are checked as a scene file's and not used, so a scene file may lend its sounds.
// Throws SceneError naming the file, line and key, or a file without a [sound] table.
Sounds load_sound_set(const std::filesystem::path& path);

// The mesh file's parts through assimp, scaled by `metres_per_unit`; a part moves with the
// door when its node (or an ancestor) is named in `door_nodes`. With `names_required` every
// name must be found (mesh.door_nodes as given); without, a mesh with none of them moves
// whole (mesh.door_nodes not given: the default name "door"). A part under a node named
// "handle" takes the handle's colour, one that moves the door's, the others the cabinet's.
// Throws SceneError naming the file (assimp's reason, or a door node not found).
std::vector<MeshPart> import_mesh(const std::filesystem::path& file, double metres_per_unit,
                                  const std::vector<std::string>& door_nodes, bool names_required,
                                  const Colours& colours);

// A point of the door (scene frame, door closed) where it is at angle theta_rad.
Vec3 door_point_at(const Scene& scene, const Vec3& closed_point_m, double theta_rad);

}  // namespace doorbench::station
