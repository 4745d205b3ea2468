#pragma once
// What `doorbench play --station` opens beside a playback (docs/station.md): the scene
// and its sound files (read first, so that a bad scene stops the run before the device
// moves), then, once the playback's render loop exists, the station's window and its sound,
// each on its own thread reading the loop's DoorSnapshotChannel. A station without an audio
// output plays on silent and says so in its report. close() ends both before the playback
// (and its snapshot) goes.
//
// For a run of trials (`ab`, `campaign run`) the window stays open from start() to close()
// and follows each presentation's playback (follow(), unfollow()); the sound is opened for
// each presentation and its counts add up over the run. A presentation may be staged in
// another scene and with another sound set (a campaign variant's, stage()): every one the
// run may stage is read when the session is made, so that a switch reads no file and
// allocates nothing the tick waits for (the tick only ever writes the snapshot).
//
// Thread safety: one control thread.
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "haptic/door_snapshot.h"
#include "station/door_sound.h"
#include "station/scene.h"
#include "station/station.h"

namespace doorbench::station {

struct StationRequest {
  std::filesystem::path scene_file;  // empty: the built-in dishwasher
  StationWindowOptions window;
  bool sound = true;
  // The other scene files and sound sets (station/scene.h, load_sound_set) the run may
  // stage. A staged scene is drawn with the station's stereo settings (the screen's).
  std::vector<std::filesystem::path> scenes, sound_sets;
};

class StationSession {
 public:
  // Reads the scene, the request's other scenes and sound sets and every sound file they
  // name; throws SceneError naming the file and key.
  explicit StationSession(const StationRequest& request);
  ~StationSession();

  const Scene& scene() const { return scene_; }
  // Opens the window reading `snapshot` (which must outlive close()); throws
  // std::runtime_error when it cannot (no display, no such display: the message says).
  void open(const haptic::DoorSnapshotChannel& snapshot);
  // Opens the window following no playback (the door rests closed); throws as open() does.
  void start();
  // The window and the sound follow `snapshot` (which must outlive unfollow()) from the next
  // frame; the sound's output opens now (a station without one plays on silent).
  void follow(const haptic::DoorSnapshotChannel& snapshot);
  // Stops following: the sound's output closes, the door rests closed.
  void unfollow();
  // The scene drawn from the next frame and the sounds of the next follow(): a scene file
  // and a sound set of the request (empty: the station's own scene; the staged scene's own
  // sounds). std::invalid_argument for a file the request did not name.
  void stage(const std::filesystem::path& scene_file, const std::filesystem::path& sounds_file);
  // The staged scene's Scene::source and the staged sounds' SoundSamples::source (the
  // station's own: "built-in" or the --scene file as given).
  std::string staged_scene() const;
  std::string staged_sounds() const { return staged_sounds_->source; }
  // Whether a sound output plays the followed door (false before follow(), with
  // --no-sound, or when no output could be opened).
  bool sound_playing() const { return sound_ != nullptr; }
  // Ends the window's thread; keeps its report.
  void close();
  // Two lines for the summary: frames, frame interval, stereo, any note; the sounds played.
  std::string brief_report() const;
  Station* station() { return station_.get(); }
  const Station* station() const { return station_.get(); }

 private:
  StationRequest request_;
  Scene scene_;
  std::string own_scene_name_;  // "built-in" or the --scene file as given
  SoundSamples own_sounds_;
  std::map<std::filesystem::path, std::unique_ptr<Scene>> scenes_;
  std::map<std::filesystem::path, SoundSamples> scene_sounds_, sound_sets_;
  const Scene* staged_scene_ = &scene_;
  const SoundSamples* staged_sounds_ = &own_sounds_;
  std::unique_ptr<Station> station_;
  std::optional<StationReport> report_;
  std::unique_ptr<DoorSound> sound_;
  SoundReport sound_report_;
  std::uint64_t clicks_before_ = 0, knocks_before_ = 0;  // of earlier presentations
};

}  // namespace doorbench::station
